// The online estimator's results as messages: parameters with their whole covariance by
// name, a batch calibration (in force and this batch), a batch as params_t, the verdict.
#include "kincal/online/estimate_messages.h"

#include <gtest/gtest.h>

#include <vector>

#include "lcm_round_trip.h"

namespace kincal {
namespace {

using testing::RoundTrip;

// A batch calibration of a unicycle with a delay the selection accepted.
BatchCalibration GoodBatch() {
  BatchCalibration c;
  c.sequence = 2;
  c.ok = true;
  c.effects = {"time_offset"};
  c.accepted = {"time_offset"};
  c.accepted_evidence = {"time_offset accepted (held-out gain 0.6, dBIC -400)"};
  c.params = {{"k_v", "1", 0.9, 0.01, 0.008},
              {"k_omega", "1", 0.85, 0.02, 0.01},
              {"delay_s", "s", 0.2, 0.005, 0.004}};
  c.covariance = Eigen::Vector3d(1e-4, 4e-4, 2.5e-5).asDiagonal();
  c.covariance(0, 2) = c.covariance(2, 0) = 1e-5;
  c.horizon_s = 1.0;
  c.heldout_before_m = 0.05;
  c.heldout_after_m = 0.01;
  c.data_begin_ns = 1'000'000'000;
  c.data_end_ns = 61'000'000'000;
  c.num_poses = 1800;
  return c;
}

TEST(EstimateMessages, ParamsCarryValuesSigmasAndTheWholeCovarianceByName) {
  const System sys = MakeSystem("diffdrive", {"time_offset"}).value();
  StateVec x = StateVec::Zero(sys.state_dim());
  const int off = sys.param_offset();
  x.segment(off, 4) << 0.031, 0.0313, 0.148, 0.12;
  StateMat P = StateMat::Zero(4, 4);
  P << 4e-8, 1e-9, 0, 0, 1e-9, 9e-8, 0, 0, 0, 0, 1e-6, 2e-7, 0, 0, 2e-7, 2.5e-5;
  kincal::params_t m;
  FillParamsMessage(sys, x.segment(off, 4), P, "dd2", 77, 123456, &m);
  m.status = kincal::params_t::STATUS_CONVERGING;
  const kincal::params_t r = RoundTrip(m);
  EXPECT_EQ(int{r.source}, int{kincal::params_t::SOURCE_FILTER});
  ASSERT_EQ(r.num_params, 4);
  EXPECT_EQ(r.names, (std::vector<std::string>{"r_l", "r_r", "d", "delay_s"}));
  EXPECT_EQ(r.units[3], "s");
  EXPECT_DOUBLE_EQ(r.values[3], 0.12);
  EXPECT_DOUBLE_EQ(r.sigmas[0], 2e-4);
  EXPECT_DOUBLE_EQ(r.sigmas[3], 5e-3);
  EXPECT_DOUBLE_EQ(r.covariance[2][3], 2e-7);
  EXPECT_DOUBLE_EQ(r.covariance[1][0], 1e-9);
  EXPECT_EQ(r.update_count, 77);
  EXPECT_EQ(r.utime, 123456);
  EXPECT_EQ(r.model, "diffdrive");
  EXPECT_EQ(r.estimator, "dd2");
}

TEST(EstimateMessages, ACalibrationCarriesTheBatchInForceAndWhatThisBatchDid) {
  const BatchCalibration good = GoodBatch();
  BatchCalibration failed;
  failed.sequence = 3;
  failed.error = "the fit is not unique: the model explains nothing";
  failed.data_begin_ns = 1'000'000'000;
  failed.data_end_ns = 121'000'000'000;
  failed.num_poses = 3600;
  failed.compute_s = 2.5;
  kincal::calibration_t m;
  FillCalibrationMessage(failed, &good, "unicycle", 17, &m);
  const kincal::calibration_t r = RoundTrip(m);
  EXPECT_EQ(r.sequence, 3);
  EXPECT_EQ(r.ok, 0);
  EXPECT_EQ(r.error, failed.error);
  EXPECT_EQ(r.calibration_sequence, 2);  // the values are the last good batch's
  EXPECT_EQ(r.model, "unicycle+time_offset");
  EXPECT_EQ(r.effects, good.effects);
  ASSERT_EQ(r.num_params, 3);
  EXPECT_EQ(r.names, (std::vector<std::string>{"k_v", "k_omega", "delay_s"}));
  EXPECT_EQ(r.units[2], "s");
  EXPECT_DOUBLE_EQ(r.values[2], 0.2);
  EXPECT_DOUBLE_EQ(r.sigmas[1], 0.02);
  EXPECT_DOUBLE_EQ(r.covariance[0][2], 1e-5);
  EXPECT_EQ(r.accepted, good.accepted);
  EXPECT_EQ(r.accepted_evidence, good.accepted_evidence);
  EXPECT_DOUBLE_EQ(r.heldout_after_m, 0.01);
  EXPECT_EQ(r.utime, 121'000'000);  // this batch's data end (us)
  EXPECT_EQ(r.data_begin_utime, 1'000'000);
  EXPECT_EQ(r.num_poses, 3600);
  EXPECT_EQ(r.poses_thinned, 17);
  EXPECT_DOUBLE_EQ(r.compute_s, 2.5);
  // Before any good batch: no parameters, and it says there is none.
  FillCalibrationMessage(failed, nullptr, "unicycle", 0, &m);
  const kincal::calibration_t none = RoundTrip(m);
  EXPECT_EQ(none.calibration_sequence, 0);
  EXPECT_EQ(none.num_params, 0);
  EXPECT_EQ(none.model, "unicycle");
}

TEST(EstimateMessages, ABatchCalibrationAsParamsSaysItIsTheBatchs) {
  kincal::params_t m;
  FillParamsFromCalibration(GoodBatch(), "unicycle", 900, 61'000'000, &m);
  m.status = kincal::params_t::STATUS_CONVERGED;
  const kincal::params_t r = RoundTrip(m);
  EXPECT_EQ(int{r.source}, int{kincal::params_t::SOURCE_BATCH});
  EXPECT_EQ(r.estimator, "batch");
  EXPECT_EQ(r.model, "unicycle");
  ASSERT_EQ(r.num_params, 3);
  EXPECT_DOUBLE_EQ(r.values[1], 0.85);
  EXPECT_DOUBLE_EQ(r.covariance[2][0], 1e-5);
  EXPECT_EQ(r.update_count, 900);
}

TEST(EstimateMessages, ModelCheckCarriesTheVerdict) {
  ModelCheckVerdict v;
  v.consistent = false;
  v.window = 512;
  v.nis_mean = 9.5;
  v.suspected_effect = "time_offset";
  v.confidence = 0.8;
  v.evidence = "along-track";
  const auto r = RoundTrip(ModelCheckMessage(v, "unicycle", 99));
  EXPECT_EQ(r.consistent, 0);
  EXPECT_EQ(r.window, 512);
  EXPECT_DOUBLE_EQ(r.nis_mean, 9.5);
  EXPECT_EQ(r.suspected_effect, "time_offset");
  EXPECT_EQ(r.model, "unicycle");
  EXPECT_EQ(r.utime, 99);
}

}  // namespace
}  // namespace kincal
