// The online estimator as kincald configures it: every option carried from its section,
// and the prior from robot.guess, the checkpoint resumed and robot.fixed over both.
#include "daemon/filter_setup.h"

#include <gtest/gtest.h>

namespace kincal::daemon {
namespace {

TEST(FilterSetup, OptionsComeFromTheirSections) {
  DaemonConfig c;
  c.filter.type = "ukf";
  c.robot.effects = {"time_offset"};
  c.robot.fixed = {{"d", 0.3}};
  c.robot.auto_effects = true;
  c.health_rate_hz = 4;
  c.checkpoint.path = "ck.json";
  c.checkpoint.every_s = 7;
  c.calibration.every_s = 50;
  c.calibration.first_s = 20;
  c.calibration.max_poses = 5000;
  const FilterStageOptions o = FilterStageOptionsFrom(c);
  EXPECT_EQ(o.filter.type, "ukf");
  EXPECT_EQ(o.effects, c.robot.effects);
  EXPECT_EQ(o.fixed, c.robot.fixed);
  EXPECT_TRUE(o.auto_effects);
  EXPECT_DOUBLE_EQ(o.model_check_every_s, 0.25);
  EXPECT_EQ(o.checkpoint_path, "ck.json");
  EXPECT_DOUBLE_EQ(o.checkpoint_every_s, 7);
  EXPECT_DOUBLE_EQ(o.calibration.every_s, 50);
  EXPECT_DOUBLE_EQ(o.calibration.first_s, 20);
  EXPECT_EQ(o.calibration.store.max_poses, 5000);
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
}

TEST(FilterSetup, TheDrawingWinsOverTheCheckpointResumed) {
  DaemonConfig c;
  c.robot.guess = {{"d", 0.35}};
  c.robot.fixed = {{"d", 0.3}};
  const System sys = MakeSystem("diffdrive", {}).value();
  const int b = sys.ParamIndex("d"), rl = sys.ParamIndex("r_l");
  Checkpoint ck;
  ck.names = {"r_l", "d"};
  ck.values = {0.052, 0.32};
  ck.covariance = Eigen::Matrix2d::Identity() * 1e-6;
  const FilterPrior p = DaemonPrior(sys, c, ck);
  EXPECT_DOUBLE_EQ(p.mean[rl], 0.052);
  EXPECT_DOUBLE_EQ(p.covariance(rl, rl), 1e-6);
  EXPECT_DOUBLE_EQ(p.mean[b], 0.3);
  EXPECT_LT(p.covariance(b, b), 1e-12);
  EXPECT_DOUBLE_EQ(DaemonPrior(sys, DaemonConfig{}, std::nullopt).mean[b],
                   sys.params()[static_cast<size_t>(b)].default_value);
}

// --resume: nothing named, nothing read; a missing file and a checkpoint of another model
// are errors naming the file.
TEST(FilterSetup, TheCheckpointResumedIsReadAndItsModelChecked) {
  const System sys = MakeSystem("diffdrive", {}).value();
  DaemonConfig c;
  const StatusOr<std::optional<Checkpoint>> none = ReadResumed(c, sys);
  ASSERT_TRUE(none.ok()) << none.status().message();
  EXPECT_FALSE(none->has_value());
  c.checkpoint.resume = ::testing::TempDir() + "/no_such_checkpoint.json";
  const StatusOr<std::optional<Checkpoint>> missing = ReadResumed(c, sys);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("no_such_checkpoint.json"), std::string::npos);
  Checkpoint ck;
  ck.model = "unicycle";
  ck.filter = "dd2";
  ck.names = {"k_v", "k_omega"};
  ck.units = {"1", "1"};
  ck.values = {0.9, 0.8};
  ck.covariance = Eigen::Matrix2d::Identity() * 1e-4;
  c.checkpoint.resume = ::testing::TempDir() + "/unicycle_checkpoint.json";
  ASSERT_TRUE(WriteCheckpoint(c.checkpoint.resume, ck).ok());
  const StatusOr<std::optional<Checkpoint>> other = ReadResumed(c, sys);
  ASSERT_FALSE(other.ok());
  EXPECT_NE(other.status().message().find("checkpoint is for model 'unicycle', the config says "
                                          "'diffdrive'"),
            std::string::npos)
      << other.status().message();
  const StatusOr<std::optional<Checkpoint>> same =
      ReadResumed(c, MakeSystem("unicycle", {}).value());
  ASSERT_TRUE(same.ok()) << same.status().message();
  ASSERT_TRUE(same->has_value());
  EXPECT_EQ(same.value()->values, ck.values);
}

}  // namespace
}  // namespace kincal::daemon
