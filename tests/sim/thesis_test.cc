// The thesis experiment reproduced: joint calibration over the 99 runs reaches the
// target NNDE and the Bayesian Cramer-Rao bound, for every estimator.
#include "kincal/sim/thesis.h"

#include <gtest/gtest.h>

namespace kincal {
namespace {

// The experiment, which must run: an error fails the test (and leaves an empty result).
ThesisResult Reproduce(const ThesisOptions& o) {
  StatusOr<ThesisResult> r = ReproduceThesis(o);
  if (!r.ok()) {
    ADD_FAILURE() << r.status().message();
    return {};
  }
  return std::move(r).value();
}

TEST(Thesis, TablesTranscribedIntact) {
  // Spot checks against the printed tables.
  EXPECT_EQ(kThesisControls[0][0], 2.3);
  EXPECT_EQ(kThesisControls[97][1], 6.0);
  EXPECT_EQ(kThesisControls[98][0], 45.3);
  EXPECT_EQ(kThesisEstimates[2][2], 144.610);
  // The thesis's 0.466 % is the NNDE of the mean of Table 6-5.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& row : kThesisEstimates) mean += Eigen::Vector3d(row[0], row[1], row[2]);
  mean /= 99.0;
  EXPECT_NEAR(100.0 * Nnde(mean * 1e-3, Eigen::Vector3d(kThesisRL, kThesisRR, kThesisD)),
              kThesisNndePercent, 0.002);
}

// Options that cannot be had are an error naming them, never an exception or a run.
TEST(Thesis, OptionsThatCannotBeHadAreAnError) {
  ThesisOptions o;
  o.runs = 0;
  StatusOr<ThesisResult> r = ReproduceThesis(o);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message().rfind("thesis: ", 0), 0u) << r.status().message();
  // Centres scattered by 1.9 px: noise that much breaks the detection (the meter says so).
  o = ThesisOptions::Realistic();
  o.runs = 1;
  o.pixel.centroid_sigma_px = 1.9;
  r = ReproduceThesis(o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("cannot be made to scatter by 1.900000 px"),
            std::string::npos)
      << r.status().message();
  // A calibration board of 1 m squares: most of it outside the view, no day's calibration.
  o = ThesisOptions::Realistic();
  o.runs = 1;
  o.pixel.calibration.board_pitch_m = 1.0;
  r = ReproduceThesis(o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("thesis: experiment 1: the day's camera calibration: "),
            std::string::npos)
      << r.status().message();
}

TEST(Thesis, JointCalibrationReachesTargetAndBound) {
  ThesisOptions o;
  o.trials = 8;
  o.seed = 2003;
  const ThesisResult r = Reproduce(o);
  ASSERT_GT(r.joint_bound_nnde_percent, 0.0);
  for (const char* name : {"dd2", "ekf", "ukf", "batch"}) {
    const double v = r.joint_nnde_percent.at(name);
    EXPECT_LE(v, 0.1) << name;
    EXPECT_LE(v, 1.2 * r.joint_bound_nnde_percent) << name;
    EXPECT_GE(r.joint_within_3sigma.at(name), 0.9) << name;
  }
  // Per experiment the prior dominates one direction; DD2 stays near that bound.
  EXPECT_LE(r.per_run_nnde_percent.at("dd2"), 1.2 * r.per_run_bound_nnde_percent);
}

// Issue 18: the bound checked two-sided. Every estimator landed at 0.79-0.93 of the bound
// in runs of 8 to 100 trials, which suggested a bound 10 % high. On 600 trials of a short
// design (12 of the runs, so that it stays quick) the mean-square error of the efficient
// joint estimators over the bound's has a 95 % interval that contains 1: the bound is
// neither high nor low by more than the interval's half-width.
TEST(Thesis, EfficientJointEstimatorsMeetTheBoundTwoSided) {
  ThesisOptions o;
  o.runs = 12;
  o.trials = 600;
  o.seed = 11;
  o.filters = {"dd2", "ukf"};
  o.batch = true;
  o.per_run = false;
  const ThesisResult r = Reproduce(o);
  for (const std::string name : {"dd2", "ukf", "batch"}) {
    const BoundRatio b = RatioToBound(r, name);
    std::cout << name << ": mean-square NNDE / bound = " << b.ratio << " [" << b.low << ", "
              << b.high << "] over " << b.trials << " trials\n";
    EXPECT_EQ(b.trials, 600);
    EXPECT_LT(b.high - b.low, 0.3) << "interval too wide to tell";
    EXPECT_LE(b.low, 1.0) << name << " beats the bound: the bound is too high";
    EXPECT_GE(b.high, 1.0) << name << " misses the bound: not efficient, or the bound too low";
  }
}

// Issue 18, the systematic errors the idealised world lacks: the wheels turn at the rate
// the look-up table gives for the quantised, saturated command, off by a gain per wheel
// and speed band.
TEST(ThesisWheelErrors, QuantisedSaturatedAndScaledPerBand) {
  WheelRateErrors e;
  e.command_step_rad_s = 0.1;
  e.max_rad_s = 40.0;
  e.band_width_rad_s = 5.0;
  const std::vector<std::array<double, 2>> gains = {{0.01, -0.02}, {0.0, 0.03}};
  EXPECT_NEAR(RealisedWheelRate(2.34, 0, e, {}), 2.3, 1e-12);  // quantised only
  EXPECT_NEAR(RealisedWheelRate(2.34, 0, e, gains), 2.3 * 1.01, 1e-12);
  EXPECT_NEAR(RealisedWheelRate(2.34, 1, e, gains), 2.3 * 0.98, 1e-12);
  EXPECT_NEAR(RealisedWheelRate(-7.26, 1, e, gains), -7.3 * 1.03, 1e-12);  // band 1
  EXPECT_NEAR(RealisedWheelRate(45.3, 0, e, gains), 40.0, 1e-12);          // saturated, last band
  WheelRateErrors none;
  EXPECT_EQ(RealisedWheelRate(2.34, 0, none, {}), 2.34);
  std::string error;
  e.gain_sigma = -1;
  EXPECT_FALSE(e.IsValid(&error));
  EXPECT_NE(error.find("gain_sigma"), std::string::npos);
}

// The errors reach the simulated truth and not the estimators: with them the joint
// estimate moves far beyond the bound (the bare model cannot absorb a per-band gain), and
// the idealised result is unchanged when they are zero.
TEST(ThesisWheelErrors, ReachTheTruthNotTheEstimators) {
  ThesisOptions o;
  o.runs = 20;
  o.trials = 4;
  o.filters = {"dd2"};
  o.batch = false;
  o.per_run = false;
  const ThesisResult ideal = Reproduce(o);
  o.wheel.gain_sigma = 0.003;
  o.wheel.command_step_rad_s = 0.1;
  o.stamp_step_s = 0.01;
  const ThesisResult real = Reproduce(o);
  const double ratio_ideal = ideal.joint_nnde_percent.at("dd2") / ideal.joint_bound_nnde_percent;
  const double ratio_real = real.joint_nnde_percent.at("dd2") / real.joint_bound_nnde_percent;
  std::cout << "joint DD2 NNDE: idealised " << ideal.joint_nnde_percent.at("dd2") << " % ("
            << ratio_ideal << " x bound), with wheel-rate errors "
            << real.joint_nnde_percent.at("dd2") << " % (" << ratio_real << " x bound, "
            << 100 * real.joint_within_3sigma.at("dd2") << " % within 3 sigma)\n";
  EXPECT_LT(ratio_ideal, 1.5);
  EXPECT_GT(ratio_real, 10.0);
}

// Reproduces the timer tick's second-order bias first: a pose stamped within a tick lies
// on the arc ahead of or behind its stamp, so seen along its own heading it sits outside
// the arc it is compared with by e^2 / 2 v w on average. Treated as first-order noise
// only, that grew every circle (joint DD2 1e-4 of the lengths off at a 10 ms tick, 4e-4
// at 20 ms: NEES 30 and 400). With the term's mean taken out the estimate is within the
// bound and honest.
TEST(ThesisTimerTick, StampsOnATickLeaveTheJointEstimateUnbiased) {
  ThesisOptions o;
  o.trials = 3;
  o.seed = 7;
  o.frames_per_run = 128;
  o.stamp_step_s = 0.02;
  o.filters = {"dd2"};
  o.batch = false;
  o.per_run = false;
  const ThesisResult r = Reproduce(o);
  const double nnde = r.joint_nnde_percent.at("dd2");
  std::cout << "20 ms tick: joint DD2 " << nnde << " % (bound " << r.joint_bound_nnde_percent
            << " %), NEES " << r.joint_nees.at("dd2") << ", "
            << 100 * r.joint_within_3sigma.at("dd2") << " % within 3 sigma\n";
  EXPECT_LT(nnde, 2.0 * r.joint_bound_nnde_percent);
  EXPECT_LT(r.joint_nees.at("dd2"), 8.0);
  EXPECT_EQ(r.joint_within_3sigma.at("dd2"), 1.0);
}

}  // namespace
}  // namespace kincal

namespace kincal {
namespace {

// Table 6-5's per-run statistics against the nominal robot, as docs/thesis.md quotes them.
TEST(Thesis, TableStatistics) {
  const TableStats s = ThesisTableStats();
  EXPECT_NEAR(100 * s.mean_nnde, 0.709, 0.001);
  EXPECT_NEAR(100 * s.nnde_of_mean, 0.465, 0.001);
  EXPECT_NEAR(100 * s.speed_scatter, 0.256, 0.002);
  EXPECT_NEAR(100 * s.turn_scatter, 0.072, 0.001);
}

// Issue 18: the realistic world. Poses through the Table 6-3 camera's pixels, wheels on a
// look-up table with gain errors per band, 0.1 rad/s commands, a 10 ms timer, 128 frames
// per run, estimators started at the nominal robot. The bare model cannot absorb the
// gains and claims a hundred times too much; with the gains as nuisance parameters DD2
// reaches 0.1 % and is honest: every error inside 3 sigma (the goal: 90 %) and the NEES
// below its chi-square's 99.7 % point. (Before the poses went onto the floor at the
// plate's known height and the tick's second-order term was taken out, the NEES was
// about 8 over trials and a third of the errors fell outside.) The per-run turn-rate
// scatter is Table 6-5's (the tuned value).
// Issue 34: the camera calibrated anew each day of ten runs (its own error drawn from the
// calibration itself). The poses' NEES is judged against what the day's calibration makes
// of the truth (its noise, not its calibration, is the solver's to state); the joint
// calibration takes the days' scale sigma as a consider covariance and stays honest; the
// speed scatter, which no wheel error can raise (docs/thesis.md, Tuning), rises from the
// 0.035 % of the world without it towards Table 6-5's 0.256 %.
TEST(ThesisRealistic, JointDd2WithNuisanceGainsReachesTargetHonestly) {
  ThesisOptions o = ThesisOptions::Realistic();
  o.seed = 18;
  o.filters = {"dd2"};
  o.batch = false;
  const ThesisResult r = Reproduce(o);
  const double dd2 = r.joint_nnde_percent.at("dd2"), gains = r.joint_nnde_percent.at("dd2+gains");
  const TableStats& s = r.per_run_stats.at("dd2");
  std::cout << "camera days " << r.camera_days << ", floor scale " << 100 * r.camera_scale_rms
            << " % RMS (claimed " << 100 * r.camera_scale_sigma_rms << " %); ";
  std::cout << "pose NEES " << r.pose_nees << ", " << r.frames_lost << " of "
            << r.frames + r.frames_lost << " frames lost; joint DD2 bare " << dd2 << " % (NEES "
            << r.joint_nees.at("dd2") << "), with gains " << gains << " % (NEES "
            << r.joint_nees.at("dd2+gains") << ", bound " << r.joint_gains_bound_nnde_percent
            << " %); per run: speed scatter " << 100 * s.speed_scatter << " %, turn scatter "
            << 100 * s.turn_scatter << " % (Table 6-5: 0.256, 0.072)\n";
  EXPECT_GT(r.pose_nees, 2.5);
  EXPECT_LT(r.pose_nees, 4.2);
  EXPECT_LT(r.frames_lost, r.frames / 30);
  EXPECT_LE(gains, 0.1);
  EXPECT_EQ(r.joint_within_3sigma.at("dd2+gains"), 1.0);
  EXPECT_LT(r.joint_nees.at("dd2+gains"), 14.2);
  EXPECT_GT(r.joint_nees.at("dd2"), 100.0);  // the bare model claims too much
  EXPECT_GT(s.turn_scatter, 0.5 * 0.00072);
  EXPECT_LT(s.turn_scatter, 2.0 * 0.00072);
  EXPECT_EQ(r.camera_days, 10);
  EXPECT_GT(r.camera_scale_rms, 2e-4);
  EXPECT_GT(s.speed_scatter, 2.0 * 0.00035);
  EXPECT_LT(s.speed_scatter, 0.00256);
}

}  // namespace
}  // namespace kincal
