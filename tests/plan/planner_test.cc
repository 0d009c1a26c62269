// kincal plan against the motions people use, on the issue's reference case (a
// differential drive with actuator lag, time offset and lever arm, poses at 15 Hz with
// 2 mm / 5 mrad), on a unicycle with a lag and on a tricycle; the plan keeps every robot
// within its prior in the workspace; the sigma it predicts is the sigma batch fits of
// simulated runs of it realise.
#include "kincal/plan/planner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <numbers>
#include <random>

#include "kincal/angles.h"
#include "kincal/estimation/batch.h"
#include "kincal/sim/simulator.h"
#include "kincal/sim/thesis_vision.h"
#include "plan/plan_cases.h"
#include "plan/shaping.h"
#include "sim/shipped_camera.h"

namespace kincal {
namespace {

struct PlanCase {
  System sys;
  Eigen::VectorXd p, prior_sigma;
  PlanOptions o;
};

// A robot the plan layer's tests share (plan_cases.h), with its prior as sigmas.
template <typename Shared>
PlanCase FromShared(const Shared& r) {
  return {r.sys, r.p, r.prior.diagonal().cwiseSqrt(), r.o};
}

// The reference case: lengths to 0.1 %, lag and delay to 3 ms, lever arm to 2 mm.
PlanCase PlanReference(double duration_s) {
  return FromShared(plan_testing::ReferenceRobot(duration_s));
}

PlanCase UnicycleWithLag(double duration_s) {
  return FromShared(plan_testing::UnicycleWithALag(duration_s));
}

PlanCase Tricycle(double duration_s) {
  PlanCase t{MakeSystem("tricycle").value(), {}, {}, {}};
  t.p = (Eigen::VectorXd(4) << 0.001, 0.0, 1e-4, 0.5).finished();
  t.prior_sigma = (Eigen::VectorXd(4) << 1e-4, 0.03, 1e-5, 0.05).finished();
  t.o.duration_s = duration_s;
  t.o.max_abs = {1000.0, 5000.0};
  t.o.max_accel = {2000.0, 5000.0};
  t.o.targets = (Eigen::VectorXd(4) << 1e-6, 1e-3, 1e-7, 5e-4).finished();
  return t;
}

// The plan against the fastest usual motion: the ratio of their times to the targets.
// `admissible` against those that keep every robot within the prior inside, as the plan
// does (0 when none does); `nominal` against those that stay in at the design point.
struct SpeedUps {
  double admissible = 0.0, nominal = 0.0;
};

SpeedUps SpeedUp(const PlanCase& c, const Workspace& ws, const char* label,
                 Motion* plan_out = nullptr, std::vector<Motion>* usual_out = nullptr) {
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  Motion plan;
  std::vector<Motion> usual;
  const Status s = PlanMotion(c.sys, c.p, prior, ws, c.o, &plan, &usual);
  if (plan_out != nullptr) *plan_out = plan;
  if (usual_out != nullptr) *usual_out = usual;
  EXPECT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(plan.stays_in);
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, prior, ws, c.o, plan.controls)) << label;
  EXPECT_FALSE(plan.curve.extrapolated);
  // Issue 34: the whole plan, its stop included, inside the duration.
  const int last = static_cast<int>(plan.controls.size()) - 1;
  EXPECT_NEAR(plan.controls.TimeAt(last), c.o.duration_s, 1e-9) << label;
  for (double u : plan.controls.ValuesAt(last)) EXPECT_EQ(u, 0.0) << label;
  double admissible = 0.0, nominal = 0.0;  // the best times, 0: none
  for (const Motion& m : usual) {
    std::cout << label << ": " << m.name << " " << m.curve.time_to_target_s << " s"
              << (m.stays_in ? "" : " (leaves)")
              << (m.every_robot_stays_in ? "" : " (leaves for a robot within the prior)") << "\n";
    const double t = m.curve.time_to_target_s;
    if (!m.stays_in || m.segment_starts_s.size() != 1) continue;
    if (nominal == 0.0 || t < nominal) nominal = t;
    if (m.every_robot_stays_in && (admissible == 0.0 || t < admissible)) admissible = t;
  }
  const double own = plan.curve.time_to_target_s;
  std::cout << label << ": " << plan.name << " " << own << " s; best usual motion that keeps every "
            << "robot within the prior inside " << admissible << " s, at the design point "
            << nominal << " s\n";
  // Issue 34: with no usual motion inside, a ratio against 1e300 passed any bound.
  EXPECT_GT(nominal, 0.0) << label << ": no usual motion stays inside the arena";
  return {admissible / own, nominal / own};
}

// A held parameter (a car's wheelbase from the drawing) is known to the plan: its value is
// the design point's, its prior sigma negligible, and it is not scored.
TEST(Plan, HeldParametersAreKnownAndNotScored) {
  const System sys = MakeSystem("bicycle").value();
  Eigen::VectorXd p(4);
  p << 1.0, 1.0, 0.0, 0.33;
  Eigen::MatrixXd prior = Eigen::MatrixXd::Identity(4, 4) * 0.01;
  prior(1, 3) = prior(3, 1) = 0.005;
  PlanOptions o;
  ASSERT_TRUE(HoldParameters(sys, {{"wheelbase", 0.26}}, &p, &prior, &o).ok());
  EXPECT_EQ(p[3], 0.26);
  EXPECT_EQ(prior(1, 3), 0.0);
  EXPECT_NEAR(std::sqrt(prior(3, 3)), kHeldSigmaFraction * sys.params()[3].default_sigma, 1e-18);
  EXPECT_EQ(o.care, (std::vector<int>{0, 1, 2}));
  const Status unknown = HoldParameters(sys, {{"wheel_base", 0.3}}, &p, &prior, &o);
  EXPECT_NE(unknown.message().find("its parameters: k_v, k_steer, steer_offset, wheelbase"),
            std::string::npos)
      << unknown.message();
  EXPECT_FALSE(HoldParameters(sys,
                              {{"k_v", 1}, {"k_steer", 1}, {"steer_offset", 0}, {"wheelbase", 0.3}},
                              &p, &prior, &o)
                   .ok());
  EXPECT_EQ(HoldParameters(sys, {{"wheelbase", 0.0}}, &p, &prior, &o).message(),
            "fix: 'wheelbase' must be >= 0.001 m (its physical bound), not 0");
}

// --prior: the named parameters' sigma replaces the generic one (or the checkpoint's),
// their correlations dropped; the others are left as they were.
TEST(Plan, PriorSigmaOfNamedParameters) {
  std::unique_ptr<System> sys;
  ASSERT_TRUE(MakeSystem("diffdrive", {"actuator_lag"}, {}, &sys).ok());
  Eigen::MatrixXd prior = Eigen::MatrixXd::Identity(4, 4) * 0.01;
  prior(0, 3) = prior(3, 0) = 0.002;
  ASSERT_TRUE(SetPriorSigma(*sys, {{"tau_s", 0.02}, {"r_r", 0.001}}, &prior).ok());
  EXPECT_DOUBLE_EQ(prior(3, 3), 0.02 * 0.02);
  EXPECT_DOUBLE_EQ(prior(1, 1), 0.001 * 0.001);
  EXPECT_EQ(prior(0, 3), 0.0);
  EXPECT_EQ(prior(3, 0), 0.0);
  EXPECT_EQ(prior(0, 0), 0.01);
  EXPECT_EQ(prior(2, 2), 0.01);
  const Eigen::MatrixXd before = prior;
  for (const auto& bad : std::vector<std::map<std::string, double>>{{{"r_l", 0.002}, {"tau", 0.02}},
                                                                    {{"tau_s", 0.0}},
                                                                    {{"d", -0.01}, {"r_l", 0.002}},
                                                                    {{"d", std::nan("")}}}) {
    const Status s = SetPriorSigma(*sys, bad, &prior);
    EXPECT_NE(s.message().find("is not a parameter of this diffdrive system with a finite, "
                               "positive sigma (its parameters: r_l, r_r, d, tau_s)"),
              std::string::npos)
        << s.message();
  }
  EXPECT_EQ(prior, before) << "an error changes nothing";
}

// The plan and the usual motions that keep every robot within the prior inside, driven by
// a true robot other than the design point: their times to the targets (their sigma
// curves evaluated at that robot; the controls are the same).
PriorRobotTimes TimesFor(const PlanCase& c, const Workspace& ws, const Motion& plan,
                         const std::vector<Motion>& usual, const Eigen::VectorXd& truth) {
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  Motion own = plan;
  EvaluateMotion(c.sys, truth, prior, ws, c.o, kCurveStepS, &own);
  double best = 0.0;
  for (const Motion& m : usual) {
    if (!m.every_robot_stays_in || m.segment_starts_s.size() != 1) continue;
    // A motion stopped once it reached the targets at the design point is driven on by a
    // robot that needs longer.
    Motion at = m;
    if (!m.unstopped.empty()) at.controls = m.unstopped;
    EvaluateMotion(c.sys, truth, prior, ws, c.o, kCurveStepS, &at);
    if (best == 0.0 || at.curve.time_to_target_s < best) best = at.curve.time_to_target_s;
  }
  EXPECT_GT(best, 0.0);
  std::cout << "  the plan " << own.curve.time_to_target_s << " s, the best usual motion " << best
            << " s\n";
  return {"", best, own.curve.time_to_target_s};
}

// The plan's own account of a robot within the prior (Motion::within_prior), or nothing.
const PriorRobotTimes* Reported(const Motion& plan, const std::string& robot) {
  for (const PriorRobotTimes& t : plan.within_prior) {
    if (t.robot == robot) return &t;
  }
  return nullptr;
}

TEST(Plan, ReferenceCaseReachesTheTargetsFasterThanEveryUsualMotion) {
  const PlanCase c = PlanReference(30.0);
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  Motion plan;
  std::vector<Motion> usual;
  const SpeedUps r = SpeedUp(c, *ws, "diffdrive + lag, delay, lever arm", &plan, &usual);
  // Measured (issue 34): 4 s (the soonest of the greedy designs under each criterion,
  // refined: D-optimal's here; 6 s under the default criterion alone) against a
  // figure-eight's 6.75 s, stopped once it reaches the targets (every robot within the
  // prior survives that; the same figure-eight driven on for the 30 s does not): 1.69x.
  // Until this round the usual motions were judged whole, and a circle each way's 15.5 s
  // made the plan look 2.6x faster than the best of them.
  EXPECT_GE(r.admissible, 1.5);
  EXPECT_GE(r.nominal, 1.5);
  // Issue 34: for the true robot anywhere within the prior's 3 sigma, not only at the
  // guess: each parameter at +-3 sigma, the plan and the usual motions (the stopped one
  // driven on until it reaches the targets) evaluated at that robot. Measured 1.18x to
  // 4.9x, 1.5x or more at 12 of the 16 robots (1.0x to 4.9x and 11 before the plan was
  // designed on for the robots short of the targets). This case's prior is tighter and its
  // wheels faster than issue 34's command (Issue34Command..., >= 1.73x everywhere): its
  // plan reaches the targets at 4 s, before the delay's -3 sigma robot, whose best usual
  // motion needs 6.5 s, could be served; even a plan designed at that robot itself is short of
  // 1.5x there (docs/plan.md). It is never worse than the best usual motion.
  // The lag's -3 sigma is below zero: 0.02 s instead (-0.8 sigma); as the lag vanishes it
  // cannot be told from the delay by any motion within the acceleration limits.
  std::vector<double> ratios;
  for (int i = 0; i < static_cast<int>(c.p.size()); ++i) {
    for (const double k : {-3.0, 3.0}) {
      Eigen::VectorXd truth = c.p;
      truth[i] += k * c.prior_sigma[i];
      if (i == 3 && k < 0) truth[i] = 0.02;  // the lag, kept physical (above)
      const PriorRobotTimes times = TimesFor(c, *ws, plan, usual, truth);
      const double ratio = SpeedUp(times);
      const std::string robot =
          c.sys.params()[static_cast<size_t>(i)].name + (k < 0 ? " -3 sigma" : " +3 sigma");
      std::cout << "true " << robot << ": " << ratio << "x\n";
      // What the plan reports for that robot is what driving it there gives; the lag's -3
      // sigma (-0.2 s) is no robot and is not reported.
      const PriorRobotTimes* reported = Reported(plan, robot);
      if (i == 3 && k < 0) {
        EXPECT_EQ(reported, nullptr);
      } else if (reported == nullptr) {
        ADD_FAILURE() << robot << " is not reported";
      } else {
        EXPECT_DOUBLE_EQ(reported->plan_s, times.plan_s) << robot;
        EXPECT_DOUBLE_EQ(reported->usual_s, times.usual_s) << robot;
      }
      EXPECT_GE(ratio, 1.0) << c.sys.params()[static_cast<size_t>(i)].name << " at " << k;
      ratios.push_back(ratio);
    }
  }
  std::sort(ratios.begin(), ratios.end());
  EXPECT_GE(ratios[ratios.size() / 2], 1.5) << "the median robot at 3 sigma";
  // The design point and the 15 physical robots at 3 sigma are reported; the least
  // speed-up among them is the delay's -3 sigma (measured 1.18x).
  ASSERT_EQ(plan.within_prior.size(), 16u);
  EXPECT_EQ(plan.within_prior[0].robot, "the design point");
  EXPECT_DOUBLE_EQ(plan.within_prior[0].plan_s, plan.curve.time_to_target_s);
  EXPECT_DOUBLE_EQ(plan.within_prior[0].usual_s, r.admissible * plan.curve.time_to_target_s);
  const std::pair<double, std::string> least = LeastSpeedUp(plan);
  EXPECT_EQ(least.second, "delay_s -3 sigma");
  EXPECT_DOUBLE_EQ(least.first, ratios.front());
}

// Issue 34: on its own command, >= 1.5x less driving than the best usual motion for the
// true robot anywhere within the prior's 3 sigma. Judged at the 16 robots the plan reports
// (the design point and +-3 sigma along each axis), at the issue's true robot (both radii
// 10 % below the guess) and at 200 robots drawn inside the 3-sigma ellipsoid, where it
// holds at 19 in 20 and not everywhere (below). Measured:
// 1.73x to 2.87x at the 16, least at the lag's +3 sigma (6.5 s against 11.25 s); the robot
// with the right wheel at +3 sigma (45 % larger) 1.87x, 0.89x before the plan was designed
// on for the robots short of the targets (src/plan/judged_design.h).
TEST(Plan, Issue34CommandIs1_5xFasterAtThePriorsAxesAndMostlyInside) {
  const PlanCase c = FromShared(plan_testing::Issue34Command());
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  Motion plan;
  std::vector<Motion> usual;
  const SpeedUps r = SpeedUp(c, *ws, "issue 34's command", &plan, &usual);
  EXPECT_GE(r.admissible, 1.5);
  ASSERT_EQ(plan.within_prior.size(), 16u);
  for (const PriorRobotTimes& t : plan.within_prior) {
    std::cout << t.robot << ": the plan " << t.plan_s << " s, the usual motion " << t.usual_s
              << " s\n";
    EXPECT_GE(SpeedUp(t), 1.5) << t.robot;
  }
  Eigen::VectorXd truth = c.p;
  truth[0] = truth[1] = 0.03;
  const PriorRobotTimes issue = TimesFor(c, *ws, plan, usual, truth);
  EXPECT_GE(SpeedUp(issue), 1.5) << "the issue's true robot";
  // Inside the ellipsoid: 200 robots, each a direction drawn uniformly and a radius up to
  // 3 sigma drawn so the robots fill the ellipsoid evenly (most of its volume is near its
  // surface), the lag kept above 0.02 s as in the reference case. Measured: 1.19x to 4.4x;
  // 190 of the 200 at 1.5x or more, the 10 short of it all near the surface (2.3 to 3
  // sigma), mostly a wheel smaller and the lag longer, where the quickest usual motion needs
  // only 9 to 12 s. (A plan designed at each of the ten, told the truth, is itself short of
  // 1.5x at five of them, and at one whichever of four searches; a sequence refined for 48
  // robots at once gains two to four of the 200 at 3.5x the planning time: docs/plan.md.)
  std::mt19937 rng(34);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit;
  std::vector<double> speedups;
  for (int k = 0; k < 200; ++k) {
    Eigen::VectorXd dir(c.p.size());
    for (int i = 0; i < dir.size(); ++i) dir[i] = gauss(rng);
    const double radius = 3.0 * std::pow(unit(rng), 1.0 / static_cast<double>(dir.size()));
    truth = c.p + radius * dir.normalized().cwiseProduct(c.prior_sigma);
    truth[3] = std::max(truth[3], 0.02);
    speedups.push_back(SpeedUp(TimesFor(c, *ws, plan, usual, truth)));
  }
  std::sort(speedups.begin(), speedups.end());
  const auto at_least = std::lower_bound(speedups.begin(), speedups.end(), 1.5);
  std::cout << "inside the ellipsoid: " << speedups.front() << "x to " << speedups.back() << "x, "
            << speedups.end() - at_least << " of 200 at 1.5x or more\n";
  EXPECT_GE(speedups.front(), 1.15) << "never near the usual motion's time";
  EXPECT_GE(speedups.end() - at_least, 185) << "1.5x or more at nine in ten and more";
}

TEST(Plan, UnicycleWithALagAndATricycle) {
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const PlanCase u = UnicycleWithLag(30.0);
  // Every motion reaches these targets within seconds. Measured 3 s against the best
  // usual motion every robot within the prior survives, 3.75 s (1.25x), and the best at the
  // design point only, a figure-eight's 3.25 s (1.08x).
  const SpeedUps uni = SpeedUp(u, *ws, "unicycle + lag");
  EXPECT_GE(uni.admissible, 1.2);
  EXPECT_GE(uni.nominal, 1.0);

  const PlanCase t = Tricycle(30.0);
  // Its tightest turn (0.66 m at 0.7 rad of steering) needs a larger floor for the usual
  // motions to fit; none keeps every robot within the prior inside even there (a turn
  // radius uncertain by a tenth), and at the design point the best needs 510 s (51x).
  EXPECT_GE(SpeedUp(t, *MakeArena(-3.0, -2.0, 3.0, 2.0), "tricycle").nominal, 1.0);
}

// 200 robots drawn from the prior (inside its 3-sigma ellipsoid) driven open loop along the
// plan: the target never leaves the camera's view. The workspace is a real camera's view:
// the shipped simulated camera (640x480, f 500 px, 2 m up), markers 10 px inside.
TEST(Plan, EveryRobotWithinThePriorStaysInView) {
  PlanCase c = PlanReference(20.0);
  const vision::CameraModel cam = vision::CameraModel::Centred(640, 480, 500.0);
  const auto ws =
      MakeCameraView(cam, vision::NadirFloor(2.0), vision::TargetLayout::Thesis(), 0.1, 10.0);
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  // Slower wheels: the view is 2.5 x 1.9 m.
  c.o.max_abs = {12.0, 12.0};
  Motion plan;
  const Status s = PlanMotion(c.sys, c.p, prior, *ws, c.o, &plan);
  ASSERT_TRUE(s.ok()) << s.message();
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<TimeNs> times;
  for (double t = 0.0; t <= c.o.duration_s + 2.0; t += 0.02) times.push_back(SecondsToNs(t));
  int drawn = 0;
  double farthest = 0.0;
  while (drawn < 200) {
    Eigen::VectorXd z(c.p.size());
    for (int i = 0; i < z.size(); ++i) z[i] = g(rng);
    if (z.norm() > 3.0) continue;
    ++drawn;
    const Eigen::VectorXd p = c.p + c.prior_sigma.cwiseProduct(z);
    const Eigen::Vector2d centre = ws->Centre();
    const VecN<kMaxState> pv = p;
    const auto traj = SimulateTruth(
        c.sys, c.sys.MakeState(centre.x(), centre.y(), 0.0, pv, ControlSignal(2, 0), 0.0),
        plan.controls, times);
    for (const auto& tp : traj) {
      ASSERT_TRUE(ws->Contains(tp.target))
          << "robot " << drawn << " at " << tp.target.transpose() << " z " << z.transpose()
          << " leaves the view at " << NsToSeconds(tp.t_ns) << " s";
      farthest = std::max(farthest, (tp.target.head<2>() - centre).norm());
    }
  }
  std::cout << "200 robots within the prior stay in view; farthest " << farthest << " m from the"
            << " centre of a view " << ws->Size() << " m across\n";
  EXPECT_GT(farthest, 0.25 * ws->Size());  // it does use the view
}

// Errors of batch fits against the truth, per scored parameter, against the predicted
// sigma: their spread (each and pooled) and how many lie inside 3 sigma.
struct ErrorTally {
  std::vector<int> scored;
  Eigen::VectorXd predicted, sq;
  int trials = 0, inside = 0, total = 0;
  ErrorTally(std::vector<int> s, Eigen::VectorXd pred)
      : scored(std::move(s)),
        predicted(std::move(pred)),
        sq(Eigen::VectorXd::Zero(predicted.size())) {}
  void Add(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
    ++trials;
    for (int i : scored) {
      const double e = estimate[i] - truth[i];
      sq[i] += e * e;
      inside += std::abs(e) <= 3.0 * predicted[i] ? 1 : 0;
      ++total;
    }
  }
  double Ratio(int i) const { return std::sqrt(sq[i] / trials) / predicted[i]; }
  double Pooled() const {
    double p = 0.0;
    for (int i : scored) p += Ratio(i) * Ratio(i);
    return std::sqrt(p / static_cast<double>(scored.size()));
  }
};

// Batch fits of simulated runs of `m` (truth drawn near the design point, Gaussian poses):
// each parameter's error spread is its predicted sigma (m's curve at its end) within 35 %,
// pooled within 20 %, and the errors lie inside 3 sigma.
void ExpectRealisedSigma(const PlanCase& c, const Motion& m, int trials, uint64_t seed,
                         const char* label) {
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  const Eigen::VectorXd predicted = m.curve.sigma.back();
  const Eigen::Vector3d sigma = c.o.info.pose_sigma;
  std::vector<TimeNs> times;
  for (double t = 0.0; t <= c.o.duration_s + 1e-9; t += 1.0 / c.o.info.pose_rate_hz) {
    times.push_back(SecondsToNs(t));
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  ErrorTally tally(ScoredParams(c.o, static_cast<int>(c.p.size())), predicted);
  for (int k = 0; k < trials; ++k) {
    // The truth drawn from the prior the motion was made for.
    Eigen::VectorXd truth = c.p;
    for (int i = 0; i < truth.size(); ++i) truth[i] += 0.1 * c.prior_sigma[i] * g(rng);
    const VecN<kMaxState> tv = truth;
    const auto traj = SimulateTruth(
        c.sys, c.sys.MakeState(0, 0, 0, tv, ControlSignal(c.sys.num_controls(), 0), 0.0),
        m.controls, times);
    const auto meas = MeasurePoses(traj, sigma.cwiseAbs2().asDiagonal(), 0, rng);
    BatchOptions bo;
    bo.prior = ParamPrior{c.p, prior};
    const BatchResult b = FitBatch(c.sys, m.controls, meas, c.p, bo);
    ASSERT_TRUE(b.status.ok()) << b.status.message();
    tally.Add(b.params, truth);
  }
  for (int i : tally.scored) {
    std::cout << label << ": " << c.sys.params()[static_cast<size_t>(i)].name
              << ": realised/predicted sigma " << tally.Ratio(i) << "\n";
    EXPECT_GT(tally.Ratio(i), 0.65);
    EXPECT_LT(tally.Ratio(i), 1.35);
  }
  std::cout << label << ": pooled realised/predicted " << tally.Pooled() << ", " << tally.inside
            << " of " << tally.total << " errors inside 3 sigma\n";
  EXPECT_NEAR(tally.Pooled(), 1.0, 0.2);
  EXPECT_GE(tally.inside, tally.total * 97 / 100);
}

// The plan's predicted sigma, realised (ExpectRealisedSigma).
void ExpectPredictedSigmaGaussian(const PlanCase& c, int trials, uint64_t seed, const char* label) {
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  Motion plan;
  ASSERT_TRUE(PlanMotion(c.sys, c.p, prior, *ws, c.o, &plan).ok());
  ExpectRealisedSigma(c, plan, trials, seed, label);
}

TEST(Plan, RealisedSigmaIsThePredictedSigma) {
  ExpectPredictedSigmaGaussian(PlanReference(15.0), 40, 8, "diffdrive + lag, delay, lever arm");
}

// The motion the plan is compared with is held to the same account: the best figure-eight
// of the reference case (stopped once at the targets), fitted as the plan is. A predicted
// sigma too large for the usual motions would flatter every speed-up. Its lag and delay
// are what keep it from the targets: each ramp between the two circles shifts the response
// about as a delay does, and only the ramps' ends tell the lag from the delay.
TEST(Plan, RealisedSigmaIsThePredictedSigmaForTheBestFigureEight) {
  const PlanCase c = PlanReference(15.0);
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  const std::vector<Motion> usual = UsualMotions(c.sys, c.p, prior, *ws, c.o);
  const auto eight = std::find_if(usual.begin(), usual.end(), [](const Motion& m) {
    return m.name.starts_with("figure-eight") && m.every_robot_stays_in;
  });
  ASSERT_NE(eight, usual.end());
  std::cout << eight->name << "\n";
  ExpectRealisedSigma(c, *eight, 40, 11, "the best figure-eight");
}

TEST(Plan, RealisedSigmaIsThePredictedSigmaForAUnicycleAndATricycle) {
  ExpectPredictedSigmaGaussian(UnicycleWithLag(8.0), 40, 9, "unicycle + lag");
  ExpectPredictedSigmaGaussian(Tricycle(8.0), 40, 10, "tricycle");
}

// Issue 34's evaluator measured that a figure-eight of two 0.2 m circles at full wheel
// speed reaches its targets in 7.13 s at the issue's true robot. By this planner's account
// (whose figure-eights the test above confirms by fits) that holds only when the wheels
// switch between the circles in steps: at the command's 20 rad/s^2 each switch is a 0.64 s
// ramp, which shifts the response about as a delay does, and the lag and the delay are
// still 1.7x their targets at 7.25 s.
double TwoCirclesTimeToTargets(double accel, double radius) {
  PlanCase c = FromShared(plan_testing::Issue34Command());
  c.o.max_accel = {accel, accel};
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  Eigen::VectorXd truth = c.p;
  truth[0] = truth[1] = 0.03;
  // The outer wheel at its limit.
  const double v = 0.999 * c.o.max_abs[0] * truth[0] * radius / (radius + 0.5 * truth[2]);
  Motion m;
  m.controls = ControlSignal(2, 0);
  m.segment_starts_s = {0.0};
  plan_internal::Values now{};
  const double loop_s = 2.0 * std::numbers::pi * radius / v;
  double t = 0.0;
  for (int k = 0; t < 50.0; ++k, t += loop_s) {
    plan_internal::Values to{};
    EXPECT_TRUE(
        plan_internal::TwistToControls(c.sys, truth, v, (k % 2 ? -v : v) / radius, c.o, &to));
    plan_internal::AppendSlewed(&m.controls, t, t + loop_s, to, c.o, &now);
  }
  plan_internal::AppendStopAndRest(&m.controls, t, c.o.duration_s, c.o, &now);
  EvaluateMotion(c.sys, truth, c.prior_sigma.cwiseAbs2().asDiagonal(), *ws, c.o, kCurveStepS, &m);
  EXPECT_TRUE(m.stays_in);
  std::cout << "two circles of " << radius << " m, wheels at " << accel
            << " rad/s^2: " << m.curve.time_to_target_s << " s\n";
  return m.curve.time_to_target_s;
}

TEST(Plan, TheIssuesFigureEightReachesTheTargetsIn7sOnlyWithSteps) {
  EXPECT_NEAR(TwoCirclesTimeToTargets(1e4, 0.2), 7.13, 0.5);  // measured 7.25 s
  EXPECT_GT(TwoCirclesTimeToTargets(20.0, 0.2), 14.0);        // 15.5 s
}

// The pose noise of a camera's images, over poses across the view: the scatter of the
// errors about their mean (the centres' small biases vary with where a marker falls on
// the pixel grid, and over a path they are noise; their common part, an offset of every
// pose, is a shift of the path that the fits' free start pose takes up).
Eigen::Vector3d MeasuredPoseSigma(PixelPoseMeter& meter, std::mt19937_64& rng) {
  constexpr int kPoses = 200;
  std::vector<Eigen::Vector3d> errors;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::uniform_real_distribution<double> pos(-0.5, 0.5), ang(-3.0, 3.0);
  int lost = 0;  // refused by the fit's chi-square (a misdetection): rare, as on the path
  for (int k = 0; k < kPoses && lost <= kPoses; ++k) {
    Eigen::Vector3d z;
    Eigen::Matrix3d R;
    const Eigen::Vector3d at(pos(rng), pos(rng), ang(rng));
    if (!meter.Measure(at, rng, &z, &R)) {
      ++lost;
      --k;
      continue;
    }
    Eigen::Vector3d e = z - at;
    e.z() = WrapAngle(e.z());
    errors.push_back(e);
    mean += e / kPoses;
  }
  EXPECT_LE(lost, kPoses / 100);
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  for (const auto& e : errors) sq += (e - mean).cwiseAbs2();
  std::cout << "pose errors across the view: mean " << mean.transpose() << ", scatter "
            << (sq / kPoses).cwiseSqrt().transpose() << "\n";
  return (sq / kPoses).cwiseSqrt();
}

// The plan's true path rendered by the shipped camera, markers detected to sub-pixel,
// Lowe's pose on the floor at the plate's height, every frame; the plan made in that
// camera's view for the pose noise across it, its sigma predicted with the noise along its
// path. Over `trials` batch fits (each frame weighted by its pose covariance) the errors'
// spread is the predicted sigma within 20 % (pooled) and they lie inside 3 sigma.
void ExpectPredictedSigmaThroughPixels(PlanCase c, int trials, uint64_t seed, const char* label) {
  const ThesisVision v = test_util::ShippedCamera();
  std::mt19937_64 rng(seed);
  PixelPoseOptions po;
  po.centroid_sigma_px = 0.05;  // about 12 grey levels of image noise; 0.1 px breaks detection
  // Rendered finely enough that the poses carry no fixed pattern (4x leaves one of about
  // 0.2 mrad of heading that white-noise information cannot know: the tricycle's steering
  // scale was then 1.5x its predicted sigma; PixelPoseMeter.FinerSupersamplingShrinks...).
  po.supersample = 8;
  auto made = PixelPoseMeter::Make(v, po, rng);
  ASSERT_TRUE(made.ok()) << made.status().message();
  PixelPoseMeter& meter = **made;
  c.o.info.pose_sigma = MeasuredPoseSigma(meter, rng);
  const auto ws = MakeCameraView(v.camera, v.floor, v.layout, v.target_height_m, 10.0);
  const Eigen::MatrixXd prior = c.prior_sigma.cwiseAbs2().asDiagonal();
  Motion plan;
  const Status planned = PlanMotion(c.sys, c.p, prior, *ws, c.o, &plan);
  ASSERT_TRUE(planned.ok()) << planned.message();
  const Eigen::Vector2d centre = ws->Centre();
  std::vector<TimeNs> times;
  for (double t = 0.0; t <= c.o.duration_s + 1e-9; t += 1.0 / c.o.info.pose_rate_hz) {
    times.push_back(SecondsToNs(t));
  }
  const VecN<kMaxState> tv = c.p;
  const auto traj = SimulateTruth(
      c.sys,
      c.sys.MakeState(centre.x(), centre.y(), 0.0, tv, ControlSignal(c.sys.num_controls(), 0), 0.0),
      plan.controls, times);
  // Each trial renders this path anew and fits it; the first renderings also give the
  // pose noise where the plan goes (its headings and places), which the sigma it
  // predicts is then evaluated with.
  std::vector<std::vector<PoseMeasurement>> runs(static_cast<size_t>(trials));
  Eigen::Vector3d path_sq = Eigen::Vector3d::Zero();
  int path_n = 0, lost = 0;
  for (auto& meas : runs) {
    for (const auto& tp : traj) {
      PoseMeasurement m;
      m.t_ns = tp.t_ns;
      if (!meter.Measure(tp.target, rng, &m.z, &m.R)) {
        ++lost;
        continue;
      }
      Eigen::Vector3d e = m.z - tp.target;
      e.z() = WrapAngle(e.z());
      path_sq += e.cwiseAbs2();
      ++path_n;
      meas.push_back(m);
    }
  }
  c.o.info.pose_sigma = (path_sq / path_n).cwiseSqrt();
  EvaluateMotion(c.sys, c.p, prior, *ws, c.o, kCurveStepS, &plan);
  const Eigen::VectorXd predicted = plan.curve.sigma.back();
  ErrorTally tally(ScoredParams(c.o, static_cast<int>(c.p.size())), predicted);
  for (const auto& meas : runs) {
    BatchOptions bo;
    bo.prior = ParamPrior{c.p, prior};
    const BatchResult b = FitBatch(c.sys, plan.controls, meas, c.p, bo);
    ASSERT_TRUE(b.status.ok()) << b.status.message();
    tally.Add(b.params, c.p);
  }
  for (int i : tally.scored) {
    std::cout << label << ": " << c.sys.params()[static_cast<size_t>(i)].name << " predicted "
              << predicted[i] << ", realised " << tally.Ratio(i) * predicted[i] << "\n";
  }
  std::cout << label << " through pixels, " << plan.name << " (pose sigma along the path "
            << c.o.info.pose_sigma.transpose() << "): pooled realised/predicted " << tally.Pooled()
            << ", " << tally.inside << " of " << tally.total << " errors inside 3 sigma, " << lost
            << " frames lost\n";
  EXPECT_NEAR(tally.Pooled(), 1.0, 0.2) << label;
  EXPECT_GE(tally.inside, tally.total * 95 / 100) << label;
  EXPECT_LT(lost, trials * static_cast<int>(times.size()) / 100) << label;
}

TEST(Plan, RealisedSigmaIsThePredictedSigmaThroughPixels) {
  PlanCase c = PlanReference(10.0);
  c.o.max_abs = {12.0, 12.0};
  ExpectPredictedSigmaThroughPixels(c, 24, 12, "diffdrive + lag, delay, lever arm");
}

TEST(Plan, RealisedSigmaIsThePredictedSigmaThroughPixelsForAUnicycle) {
  // 48 runs: at 24 (72 errors, a pooled ratio's sampling spread about 0.08) the plan that
  // stops inside its 8 s gave 0.74 with this seed and 0.93-1.00 with four others (21-24).
  ExpectPredictedSigmaThroughPixels(UnicycleWithLag(8.0), 48, 13, "unicycle + lag");
}

TEST(Plan, RealisedSigmaIsThePredictedSigmaThroughPixelsForATricycle) {
  ExpectPredictedSigmaThroughPixels(Tricycle(8.0), 24, 14, "tricycle");
}

TEST(Plan, OptionsAreCheckedAndNamed) {
  const PlanCase c = PlanReference(10.0);
  std::string error;
  EXPECT_TRUE(c.o.IsValid(c.sys, &error)) << error;
  PlanOptions o = c.o;
  o.max_abs = {20.0};
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  EXPECT_NE(error.find("omega_r"), std::string::npos) << error;
  o = c.o;
  o.max_accel = {-1.0, 1.0};
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  EXPECT_NE(error.find("omega_l"), std::string::npos) << error;
  o = c.o;
  o.levels = 4;
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  // Issue 34's sweep: the timing's three checks were one message ("duration in (0, 3600] s,
  // rate in [1, 1000] Hz and a segment between one control period and the duration
  // expected") for `--duration 0.1` (the default segment, 0.5 s, longer than it).
  o = c.o;
  o.duration_s = 0.1;
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  EXPECT_EQ(error, "segment_s: 0.5 s is longer than the plan (duration_s 0.1 s)");
  o = c.o;
  o.segment_s = 0.01;
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  EXPECT_EQ(error, "segment_s: 0.01 s is shorter than one control period (0.05 s at 20 Hz)");
  o = c.o;
  o.duration_s = 5000.0;
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  EXPECT_EQ(error, "duration_s: in (0, 3600] s expected, not 5000");
  o = c.o;
  o.control_rate_hz = 0.5;
  EXPECT_FALSE(o.IsValid(c.sys, &error));
  EXPECT_EQ(error, "control_rate_hz: in [1, 1000] Hz expected, not 0.5");
  // A workspace too small for the start: a status, not a crash.
  Motion m;
  const auto tiny = MakeArena(0.5, 0.5, 0.6, 0.6);
  const Status s = PlanMotion(c.sys, c.p, c.prior_sigma.cwiseAbs2().asDiagonal(),
                              *MakeArena(-0.01, -0.01, 0.01, 0.01), c.o, &m);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("arena"), std::string::npos) << s.message();
  (void)tiny;
}

}  // namespace
}  // namespace kincal
