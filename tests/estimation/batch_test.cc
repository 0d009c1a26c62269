// The batch fit and its Cramer-Rao bound: a constant-control run is rank deficient (and a
// prior makes the Bayesian bound exist); the spread of 40 Monte-Carlo fits matches the
// bound; the fit recovers the truth within 3 sigma from a start 5 % off; the bound equals
// the inverse of a Fisher information built independently by finite differences.
#include "kincal/estimation/batch.h"

#include <gtest/gtest.h>

#include <random>

#include "kincal/angles.h"
#include "kincal/sim/simulator.h"
#include "kincal/sim/thesis.h"
#include "test_util.h"

namespace kincal {
namespace {

using testing::AllModelScenarios;

TEST(Bound, OneConstantControlRunCannotSeparateRadiiAndTrack) {
  const System sys = MakeSystem("diffdrive").value();
  ControlSignal u(2, 0);
  const std::array<double, 2> w = {10.0, 20.0};
  AppendConstant(&u, 0, SecondsToNs(10.0), w);
  std::mt19937_64 rng(1);
  const VecN<kMaxState> truth = testing::ToVec({0.031, 0.0313, 0.148});
  std::vector<TimeNs> times;
  for (int k = 0; k < 60; ++k) times.push_back(SecondsToNs(k / 6.0));
  const auto traj = SimulateTruth(sys, sys.MakeState(0, 0, 0, truth, u, 0), u, times);
  const auto meas = MeasurePoses(traj, Eigen::Matrix3d::Identity() * 1e-8, 0, rng);
  const Eigen::Vector3d start = traj.front().x.head(3);
  const BatchResult one = BoundAt(sys, u, meas, truth.cast<double>(), {start}, {});
  EXPECT_FALSE(one.covariance_ok) << "a single constant-control run must be rank deficient";
  // With a prior, the Bayesian bound exists.
  BatchOptions with_prior;
  with_prior.prior = ParamPrior{truth.cast<double>(), Eigen::Matrix3d::Identity() * 1e-6};
  EXPECT_TRUE(BoundAt(sys, u, meas, truth.cast<double>(), {start}, with_prior).covariance_ok);
}

TEST(Bound, BatchSpreadMatchesCramerRao) {
  // 40 Monte-Carlo repetitions of one design: the empirical variance of the batch
  // estimates must agree with the bound (within the sampling error of 40 samples).
  const System sys = MakeSystem("diffdrive").value();
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(9);
  const Eigen::Vector3d sigma(0.002, 0.002, 0.01);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 20.0, 10.0, sigma, rng);
  const Eigen::Vector3d start = d.truth.front().x.head(3);
  const BatchResult bound = BoundAt(sys, d.controls, d.meas, truth.cast<double>(), {start}, {});
  ASSERT_TRUE(bound.covariance_ok);
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  const int trials = 40;
  for (int t = 0; t < trials; ++t) {
    std::vector<TrajectoryPoint> tr = d.truth;
    const auto meas = MeasurePoses(tr, sigma.array().square().matrix().asDiagonal(), 0, rng);
    const BatchResult b = FitBatch(sys, d.controls, meas, truth.cast<double>() * 1.05, {});
    sq += (b.params - truth.cast<double>()).array().square().matrix();
  }
  for (int i = 0; i < 3; ++i) {
    const double ratio = sq[i] / trials / bound.covariance(i, i);
    EXPECT_GT(ratio, 0.5) << i;
    EXPECT_LT(ratio, 1.6) << i;
  }
}

TEST(Batch, RecoversTheTruthWithin3SigmaFromAStart5PercentOff) {
  const System sys = MakeSystem("diffdrive").value();
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(21);
  const Eigen::Vector3d sigma(0.002, 0.002, 0.01);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 20.0, 10.0, sigma, rng);
  const BatchResult b = FitBatch(sys, d.controls, d.meas, truth.cast<double>() * 1.05, {});
  ASSERT_TRUE(b.covariance_ok);
  for (int i = 0; i < 3; ++i) {
    const double err = b.params[i] - truth[i];
    const double s = std::sqrt(b.covariance(i, i));
    EXPECT_LT(std::abs(err), 3.0 * s) << sys.params()[static_cast<size_t>(i)].name;
    // A real calibration, not a loose one: each parameter to better than 1 %.
    EXPECT_LT(s, 0.01 * std::abs(truth[i])) << sys.params()[static_cast<size_t>(i)].name;
  }
}

// A held parameter (a measured track width) stays where it was put, has no variance, and
// the others are still fitted to the truth; the profiled and robust covariances agree.
TEST(Batch, FixedParameterIsHeldAndHasNoVariance) {
  const System sys = MakeSystem("diffdrive").value();
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(22);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 20.0, 10.0,
                                   Eigen::Vector3d(0.002, 0.002, 0.01), rng);
  BatchOptions o;
  o.fixed = {2};  // the track width, at its true value
  o.profiled_covariance = true;
  Eigen::VectorXd p0 = truth.cast<double>() * 1.05;
  p0[2] = truth[2];
  const BatchResult b = FitBatch(sys, d.controls, d.meas, p0, o);
  ASSERT_TRUE(b.status.ok()) << b.status.message();
  ASSERT_TRUE(b.covariance_ok);
  EXPECT_EQ(b.params[2], truth[2]);
  for (const Eigen::MatrixXd* c : {&b.covariance, &b.profiled_covariance, &b.robust_covariance}) {
    ASSERT_EQ(c->rows(), 3);
    EXPECT_EQ(c->row(2).norm(), 0.0);
    EXPECT_EQ(c->col(2).norm(), 0.0);
  }
  for (int i = 0; i < 2; ++i) {
    const double s = std::sqrt(b.covariance(i, i));
    EXPECT_LT(std::abs(b.params[i] - truth[i]), 3.0 * s);
    EXPECT_NEAR(std::sqrt(b.profiled_covariance(i, i)), s, 0.2 * s);
  }
  o.fixed = {0, 1, 2};
  EXPECT_NE(FitBatch(sys, d.controls, d.meas, p0, o).status.message().find("every parameter"),
            std::string::npos);
  o.fixed = {1, 1};
  EXPECT_FALSE(FitBatch(sys, d.controls, d.meas, p0, o).status.ok());
  o.fixed = {3};
  EXPECT_FALSE(FitBatch(sys, d.controls, d.meas, p0, o).status.ok());
}

// Bad data is a status naming the problem, never an exception (callers used to catch any
// std::exception as "the fit failed").
TEST(Batch, BadInputsAreStatusesThatSayWhatIsWrong) {
  const System sys = MakeSystem("diffdrive").value();
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(3);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 5.0, 10.0,
                                   Eigen::Vector3d(0.002, 0.002, 0.01), rng);
  const Eigen::VectorXd guess = truth.cast<double>();
  auto fit = [&](std::vector<PoseMeasurement> meas, const Eigen::VectorXd& p0) {
    BatchResult r;
    EXPECT_NO_THROW(r = FitBatch(sys, d.controls, meas, p0, {}));
    EXPECT_FALSE(r.status.ok());
    return r.status.message();
  };
  EXPECT_EQ(fit({}, guess), "batch: no pose measurements");
  auto backwards = d.meas;
  std::swap(backwards[3].t_ns, backwards[4].t_ns);
  backwards[3].segment = backwards[4].segment = 0;
  for (auto& m : backwards) m.segment = 0;
  EXPECT_EQ(fit(backwards, guess), "batch: measurement times go backwards within segment 0");
  auto singular = d.meas;
  singular[2].R = Eigen::Matrix3d::Zero();
  EXPECT_EQ(fit(singular, guess), "batch: measurement 2: covariance is not positive definite");
  EXPECT_EQ(fit(d.meas, guess.head(2)),
            "batch: the initial guess has 2 parameters, the system 3, all finite expected");
  // The same data, well formed, fits.
  EXPECT_TRUE(FitBatch(sys, d.controls, d.meas, guess, {}).status.ok());
}

// Issue 18: the bound checked independently. The Fisher information of the parameters and
// the segments' start poses, from central differences of the measurement model itself (the
// simulated target poses at the frame times), inverted, equals the covariance BoundAt gets
// from Ceres's analytic Jacobians.
struct Segment {
  Eigen::Vector3d start;
  std::vector<TimeNs> times;
};

// Target poses of one segment for parameters p and start pose s.
std::vector<Eigen::Vector3d> Measure(const System& sys, const ControlSignal& u,
                                     const Eigen::Vector3d& p, const Eigen::Vector3d& s,
                                     const std::vector<TimeNs>& times) {
  VecN<kMaxState> pv = p;
  const StateVec x0 = sys.MakeState(s.x(), s.y(), s.z(), pv, u, u.ToSeconds(times.front()));
  std::vector<Eigen::Vector3d> z;
  for (const auto& tp : SimulateTruth(sys, x0, u, times)) z.push_back(tp.target);
  return z;
}

TEST(Bound, EqualsTheInverseFisherInformationByFiniteDifferences) {
  const System sys = MakeSystem("diffdrive", {}).value();
  const Eigen::Vector3d p(kThesisRL, kThesisRR, kThesisD);
  // Four of the thesis's runs (constant wheel rates, a second apart), 6 Hz frames.
  ControlSignal u(2, 0);
  std::vector<Segment> segs;
  std::mt19937_64 rng(3);
  TimeNs t = 0;
  const int runs[] = {0, 17, 60, 98};
  for (int k : runs) {
    const std::array<double, 2> w = {kThesisControls[k][0], kThesisControls[k][1]};
    const TimeNs t1 = t + SecondsToNs(8.0);
    AppendConstant(&u, t, t1, w);
    FrameTimingOptions timing;
    timing.rate_hz = 6.0;
    Segment s;
    s.times = FrameTimes(t, t1, timing, rng);
    s.start = Eigen::Vector3d(0.05 * k / 98.0, -0.03, 0.4 + k * 0.02);
    segs.push_back(s);
    t = t1 + kNsPerSecond;
  }
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-7, 2e-7, 1e-5).asDiagonal();
  std::vector<PoseMeasurement> meas;
  std::vector<Eigen::Vector3d> starts;
  for (size_t g = 0; g < segs.size(); ++g) {
    const auto z = Measure(sys, u, p, segs[g].start, segs[g].times);
    for (size_t i = 0; i < z.size(); ++i)
      meas.push_back({segs[g].times[i], z[i], R, static_cast<int>(g)});
    starts.push_back(segs[g].start);
  }
  BatchOptions opt;
  opt.warmup_s = 0.0;
  const BatchResult bound = BoundAt(sys, u, meas, p, starts, opt);
  ASSERT_TRUE(bound.status.ok()) << bound.status.message();
  ASSERT_TRUE(bound.covariance_ok);

  // Unknowns: 3 parameters, then 3 per segment start pose. Central differences.
  const int n = 3 + 3 * static_cast<int>(segs.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  const Eigen::Matrix3d Ri = R.inverse();
  for (size_t g = 0; g < segs.size(); ++g) {
    const size_t m = segs[g].times.size();
    std::vector<Eigen::MatrixXd> H(m, Eigen::MatrixXd::Zero(3, n));
    for (int j = 0; j < n; ++j) {
      const bool is_param = j < 3;
      if (!is_param && (j - 3) / 3 != static_cast<int>(g)) continue;  // other segments' starts
      const double h = is_param ? 1e-6 * p[j] : 1e-6;
      Eigen::Vector3d pp = p, pm = p, sp = segs[g].start, sm = segs[g].start;
      if (is_param) {
        pp[j] += h;
        pm[j] -= h;
      } else {
        sp[(j - 3) % 3] += h;
        sm[(j - 3) % 3] -= h;
      }
      const auto zp = Measure(sys, u, pp, sp, segs[g].times);
      const auto zm = Measure(sys, u, pm, sm, segs[g].times);
      for (size_t i = 0; i < m; ++i) {
        Eigen::Vector3d d = zp[i] - zm[i];
        d.z() = WrapAngle(d.z());
        H[i].col(j) = d / (2 * h);
      }
    }
    for (size_t i = 0; i < m; ++i) J += H[i].transpose() * Ri * H[i];
  }
  const Eigen::Matrix3d numeric = J.inverse().topLeftCorner<3, 3>();
  const Eigen::Matrix3d analytic = bound.covariance.topLeftCorner<3, 3>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double scale = std::sqrt(analytic(i, i) * analytic(j, j));
      EXPECT_NEAR(numeric(i, j) / scale, analytic(i, j) / scale, 1e-4) << i << "," << j;
    }
  }
  std::cout << "bound sigmas (analytic): " << analytic.diagonal().cwiseSqrt().transpose()
            << "\nfinite differences:      " << numeric.diagonal().cwiseSqrt().transpose() << "\n";
}

}  // namespace
}  // namespace kincal
