// Many runs in one calibration (issue 33): each run its own start, nothing predicted,
// fitted or warmed up across a run's start, whole runs held out, per-run errors and the
// dead reckoning over each run.
#include "analysis/runs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "analysis/analysis_test_util.h"
#include "kincal/analysis/analyze.h"

namespace kincal {
namespace {

// A car (bicycle: k_v 0.95, k_steer 0.6, steer_offset 0.02 rad, wheelbase 0.33 m, a
// steering lag of 0.12 s) driven for `runs` runs of `run_s` seconds, each from its own
// place and heading and on its own epoch (as bags are), poses at 20 Hz.
std::vector<Recording> CarRuns(int runs, double run_s, uint64_t seed) {
  const System sys = MakeSystem("bicycle", {"actuator_lag[steer]"}).value();
  const VecN<kMaxState> p = ParamsFrom(sys,
                                       {{"k_v", 0.95},
                                        {"k_steer", 0.6},
                                        {"steer_offset", 0.02},
                                        {"wheelbase", 0.33},
                                        {"tau_s_steer", 0.12}},
                                       "truth")
                                .value();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> place(-2.0, 2.0), heading(-3.0, 3.0);
  std::vector<Recording> out;
  const std::array<double, 2> lo = {0.3, -0.45}, hi = {2.0, 0.45};
  for (int r = 0; r < runs; ++r) {
    Recording rec;
    rec.source = "run" + std::to_string(r + 1);
    rec.controls = ControlSignal(2, 0);
    AppendPiecewiseRandom(&rec.controls, 0, SecondsToNs(run_s), lo, hi, 0.4, 1.2, rng);
    const auto times = FrameTimes(0, SecondsToNs(run_s), FrameTimingOptions{20.0, 0, 0, 0}, rng);
    const StateVec x0 = sys.MakeState(place(rng), place(rng), heading(rng), p, rec.controls, 0.0);
    const auto traj = SimulateTruth(sys, x0, rec.controls, times);
    const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 1e-6, 9e-6).asDiagonal();
    for (const auto& m : MeasurePoses(traj, R, 0, rng)) rec.poses.push_back({m.t_ns, m.z});
    rec.stats.pose_rows = static_cast<int>(rec.poses.size());
    out.push_back(std::move(rec));
  }
  return out;
}

AnalyzeOptions CarOptions() {
  AnalyzeOptions o;
  o.model = "bicycle";
  o.fixed = {{"wheelbase", 0.33}};
  o.max_effects = 2;
  return o;
}

std::map<std::string, ParamEstimate> ByName(const FitReport& f) {
  std::map<std::string, ParamEstimate> m;
  for (const auto& p : f.params) m[p.name] = p;
  return m;
}

TEST(ManyRuns, ThirtyShortRunsCalibrateTheCarWithinThreeSigma) {
  const AnalyzeResult r = Analyze(JoinRuns(CarRuns(30, 4.0, 7)).value(), CarOptions()).value();
  ASSERT_EQ(r.runs.size(), 30u);
  for (const auto& run : r.runs) EXPECT_EQ(run.heldout, run.index % 3 == 0) << run.index;
  const auto got = ByName(r.after);
  const std::map<std::string, double> truth = {
      {"k_v", 0.95}, {"k_steer", 0.6}, {"steer_offset", 0.02}, {"tau_s_steer", 0.12}};
  for (const auto& [name, v] : truth) {
    ASSERT_TRUE(got.count(name)) << name << " missing; effects found: " << r.after.effects.size();
    EXPECT_LE(std::abs(got.at(name).value - v), 3.0 * got.at(name).sigma)
        << name << " = " << got.at(name).value << " +- " << got.at(name).sigma;
  }
  // Dead reckoning over the held-out runs: the lag found makes it better, not worse.
  EXPECT_EQ(r.heldout_dr_after.runs, 10);
  EXPECT_LT(r.heldout_dr_after.rms_m, r.heldout_dr_before.rms_m);
  EXPECT_LT(r.after.heldout.pos_rms_m, 0.7 * r.before.heldout.pos_rms_m);
}

// The runs back to back: each run's samples moved earlier so that the next run's first
// pose follows the previous run's last by one pose interval. Only the run marks separate
// them now (no gap a window could not span).
Recording BackToBack(const Recording& rec) {
  Recording out = rec;
  const TimeNs squeeze = SecondsToNs(kRunGapS) - SecondsToNs(0.05);
  auto moved = [&](TimeNs t) { return t - RunOf(rec, t) * squeeze; };
  out.controls = ControlSignal(rec.controls.num_channels(), 0);
  for (int k = 0; k < static_cast<int>(rec.controls.size()); ++k) {
    const auto& v = rec.controls.ValuesAt(k);
    out.controls.Append(moved(rec.controls.ToNs(rec.controls.TimeAt(k))),
                        std::span<const double>(v.data(), 2));
  }
  for (auto& p : out.poses) p.t_ns = moved(p.t_ns);
  for (size_t r = 0; r < out.runs.size(); ++r) out.runs[r].start_ns = moved(rec.runs[r].start_ns);
  return out;
}

// Runs are never joined: moving one run 5 m away (as if the robot had been carried there)
// changes nothing, even with the runs back to back. Without the run marks it would.
TEST(ManyRuns, MovingOneRunFiveMetresAwayChangesNothing) {
  std::vector<Recording> parts = CarRuns(9, 6.0, 11);
  AnalyzeOptions o = CarOptions();
  o.max_effects = 1;
  const Recording joined = BackToBack(JoinRuns(parts).value());
  for (auto& p : parts[4].poses) p.z.x() += 5.0;
  const Recording moved = BackToBack(JoinRuns(parts).value());
  const AnalyzeResult a = Analyze(joined, o).value(), b = Analyze(moved, o).value();
  ASSERT_EQ(a.after.params.size(), b.after.params.size());
  for (size_t i = 0; i < a.after.params.size(); ++i) {
    EXPECT_NEAR(a.after.params[i].value, b.after.params[i].value,
                1e-6 * (std::abs(a.after.params[i].value) + 1e-3))
        << a.after.params[i].name;
  }
  EXPECT_NEAR(a.after.heldout.pos_rms_m, b.after.heldout.pos_rms_m, 1e-9);
  // The test can fail: as one run, windows span the jumps between runs, and moving one
  // run changes what they see.
  Recording one = moved, one_ref = joined;
  one.runs.clear();
  one_ref.runs.clear();
  o.effects_mode = "none";
  EXPECT_GT(std::abs(Analyze(one, o).value().before.fit.pos_rms_m -
                     Analyze(one_ref, o).value().before.fit.pos_rms_m),
            0.01);
}

TEST(ManyRuns, HeldOutRunsCanBeChosenAndBadChoicesAreErrors) {
  const Recording rec = JoinRuns(CarRuns(6, 4.0, 3)).value();
  AnalyzeOptions o = CarOptions();
  o.effects_mode = "none";
  o.heldout_runs = {1, 2};
  const AnalyzeResult r = Analyze(rec, o).value();
  EXPECT_TRUE(r.runs[0].heldout && r.runs[1].heldout && !r.runs[2].heldout);
  o.heldout_runs = {7};
  EXPECT_FALSE(Analyze(rec, o).ok());
  o.heldout_runs = {1, 2, 3, 4, 5, 6};
  EXPECT_FALSE(Analyze(rec, o).ok());
}

// A run shorter than one window is skipped and said; all of them that short is an error.
TEST(ManyRuns, RunsShorterThanAWindowAreSkippedAndCounted) {
  std::vector<Recording> parts = CarRuns(7, 4.0, 5);
  std::vector<Recording> shorts = CarRuns(1, 0.6, 6);
  parts.insert(parts.begin() + 2, shorts.front());
  AnalyzeOptions o = CarOptions();
  o.effects_mode = "none";
  const AnalyzeResult r = Analyze(JoinRuns(parts).value(), o).value();
  bool said = false;
  for (const auto& w : r.warnings) said = said || w.find("skipped: run 3") != std::string::npos;
  EXPECT_TRUE(said);
  EXPECT_FALSE(Analyze(JoinRuns(CarRuns(8, 0.6, 8)).value(), o).ok());
}

// A diff drive's runs in CSV files with a run column (first, in the controls' header),
// its controls as cumulative encoder counts (4096 per revolution, whole counts): read,
// differenced into wheel rates run by run, and the wheels come back within 3 sigma.
TEST(ManyRuns, CsvRunColumnWithEncoderCountsCalibratesTheWheels) {
  const System sys = MakeSystem("diffdrive").value();
  const VecN<kMaxState> p =
      ParamsFrom(sys, {{"r_l", 0.031}, {"r_r", 0.0313}, {"d", 0.148}}, "truth").value();
  std::mt19937_64 rng(17);
  const double per_rad = 4096 / (2 * M_PI);
  std::ostringstream c, q;
  c << "run,t,omega_l,omega_r\n";
  q << "t,x,y,theta,run\n";
  c.precision(12);
  q.precision(12);
  for (int run = 1; run <= 9; ++run) {
    ControlSignal u(2, 0);
    const std::array<double, 2> lo = {-5.0, -5.0}, hi = {20.0, 20.0};
    AppendPiecewiseRandom(&u, 0, SecondsToNs(8.0), lo, hi, 0.5, 1.5, rng);
    ControlSignal grid(2, 0);  // the encoders read every 20 ms
    for (int k = 0; k <= 400; ++k) grid.Append(SecondsToNs(0.02 * k), u.At(0.02 * k));
    double angle[2] = {1000.0 * run, -500.0 * run};  // counters never reset
    for (int k = 0; k <= 400; ++k) {
      c << run << "," << 0.02 * k << "," << std::round(angle[0] * per_rad) << ","
        << std::round(angle[1] * per_rad) << "\n";
      for (int w = 0; w < 2; ++w) angle[w] += grid.At(0.02 * k)[static_cast<size_t>(w)] * 0.02;
    }
    const auto times = FrameTimes(0, SecondsToNs(8.0), FrameTimingOptions{30.0, 0, 0, 0}, rng);
    const auto traj = SimulateTruth(sys, sys.MakeState(0, 0, run, p, grid, 0.0), grid, times);
    const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 1e-6, 9e-6).asDiagonal();
    for (const auto& m : MeasurePoses(traj, R, 0, rng)) {
      q << NsToSeconds(m.t_ns) << "," << m.z.x() << "," << m.z.y() << "," << m.z.z() << "," << run
        << "\n";
    }
  }
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "/counts.csv") << c.str();
  std::ofstream(dir + "/poses.csv") << q.str();
  Recording rec = ReadCsvRecording(dir + "/counts.csv", dir + "/poses.csv",
                                   *MakeModel("diffdrive").value(), true)
                      .value();
  ASSERT_EQ(rec.runs.size(), 9u);
  ASSERT_TRUE(PositionsToRates(4096, &rec).ok());
  AnalyzeOptions o;
  o.model = "diffdrive";
  o.effects_mode = "none";
  const AnalyzeResult r = Analyze(rec, o).value();
  const auto got = ByName(r.after);
  for (const auto& [name, v] :
       std::map<std::string, double>{{"r_l", 0.031}, {"r_r", 0.0313}, {"d", 0.148}}) {
    EXPECT_LE(std::abs(got.at(name).value - v), 3.0 * got.at(name).sigma)
        << name << " = " << got.at(name).value << " +- " << got.at(name).sigma;
    EXPECT_LT(got.at(name).sigma, 0.01 * v) << name;
  }
}

// Dead reckoning at the true parameters of a clean run is exact; a wrong gain drifts.
TEST(ManyRuns, DeadReckoningIsExactAtTheTruthAndDriftsOffIt) {
  const System sys = MakeSystem("unicycle").value();
  std::mt19937_64 rng(2);
  ControlSignal u(2, 0);
  const std::array<double, 2> lo = {0.2, -1.0}, hi = {0.8, 1.0};
  AppendPiecewiseRandom(&u, 0, SecondsToNs(20.0), lo, hi, 0.5, 2.0, rng);
  const VecN<kMaxState> truth = ParamsFrom(sys, {{"k_v", 0.9}, {"k_omega", 0.8}}, "truth").value();
  Recording rec;
  rec.source = "clean";
  rec.controls = u;
  const auto times = FrameTimes(0, SecondsToNs(20.0), FrameTimingOptions{20.0, 0, 0, 0}, rng);
  for (const auto& s : SimulateTruth(sys, sys.MakeState(0, 0, 0.3, truth, u, 0.0), u, times))
    rec.poses.push_back({s.t_ns, s.target});
  AnalyzeOptions o;
  o.model = "unicycle";
  std::vector<std::string> warnings;
  const analysis::Dataset d = analysis::Prepare(rec, o, &warnings).value();
  const int last = static_cast<int>(rec.poses.size()) - 1;
  const DeadReckoning exact = analysis::DeadReckon(sys, truth.cast<double>(), d, 0, last);
  EXPECT_LT(exact.final_m, 1e-9);
  EXPECT_NEAR(exact.duration_s, NsToSeconds(rec.poses.back().t_ns), 1e-9);
  Eigen::VectorXd off = truth.cast<double>();
  off[0] *= 1.05;
  const DeadReckoning drift = analysis::DeadReckon(sys, off, d, 0, last);
  EXPECT_GT(drift.final_m, 0.1);
  EXPECT_GT(drift.rms_m, 0.01);
}

}  // namespace
}  // namespace kincal
