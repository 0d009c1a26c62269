// ReadLcmLog (src/io/lcm_log.cc): kincald's LCM logs read back as a recording, controls
// mapped onto the model's order by name; damaged ones read with warnings; a missing file
// is an error Status.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>

#include "io/io_test_util.h"
#include "kincal/io/recording.h"

namespace kincal {
namespace {

using testing::PutMessage;
class LcmLog : public testing::IoTest {};

// Five controls and five poses, one every 0.1 s from 1 s; `repeat`: then a sixth pose at the
// third's time, 9 m away.
std::string FiveOfEach(const std::filesystem::path& dir, bool repeat = false) {
  const std::string path = (dir / "run.lcm").string();
  {
    lcm::LogFile log(path, "w");
    EXPECT_TRUE(log.good());
    for (int k = 0; k < 5; ++k) {
      kincal::controls_t c{};
      c.schema_version = 1;
      c.utime = 1'000'000 + k * 100'000;
      c.model = "unicycle";
      c.num_controls = 2;
      c.names = {"omega", "v"};
      c.values = {0.1 * k, 0.5};
      PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = 1'000'000 + k * 100'000 + 50'000;
      p.x = 0.05 * k;
      p.valid = 1;
      PutMessage(log, "KINCAL_POSE", p, p.utime);
    }
    if (repeat) {
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = 1'250'000;
      p.x = 9;
      p.valid = 1;
      PutMessage(log, "KINCAL_POSE", p, p.utime);
    }
  }
  return path;
}

TEST_F(LcmLog, ReadsBack) {
  const std::string path = FiveOfEach(dir_);
  const Recording r = ReadLcmLog(path, *MakeModel("unicycle").value()).value();
  EXPECT_EQ(r.controls.size(), 5u);
  EXPECT_EQ(r.poses.size(), 5u);
  EXPECT_DOUBLE_EQ(r.origin_s, 1.0);
  EXPECT_EQ(r.controls.At(0.45)[0], 0.5);           // v, mapped by name
  EXPECT_NEAR(r.controls.At(0.45)[1], 0.4, 1e-12);  // omega
  EXPECT_NEAR(r.poses[2].z.x(), 0.1, 1e-12);
  const std::string missing = (dir_ / "none.lcm").string();
  const auto none = ReadLcmLog(missing, *MakeModel("unicycle").value());
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().message(),
            missing + ": cannot open the LCM log: No such file or directory");
}

// A log is held in memory whole: samples past the configured bound on either channel are
// refused, naming the log and the channel.
TEST_F(LcmLog, MoreSamplesThanTheBoundAreRefused) {
  const std::string path = FiveOfEach(dir_);
  const auto model = MakeModel("unicycle").value();
  RecordingLimits limits;
  limits.max_rows = 5;
  EXPECT_TRUE(ReadLcmLog(path, *model, limits).ok());
  limits.max_rows = 4;
  EXPECT_EQ(ReadLcmLog(path, *model, limits).status().message(),
            path +
                ": more than 4 samples on KINCAL_CONTROLS, the most read from one log (a "
                "recording is held in memory whole; kincal analyze --max-rows raises the bound)");
  limits.max_rows = -1;
  EXPECT_EQ(ReadLcmLog(path, *model, limits).status().message(), "max_rows -1: expected 1 or more");
}

// Two poses at one time, 9 m apart (two publishers on one channel): the later is kept, as
// at every repeated time, and said.
TEST_F(LcmLog, RepeatedTimesWithOtherValuesAreSaid) {
  const Recording r = ReadLcmLog(FiveOfEach(dir_, true), *MakeModel("unicycle").value()).value();
  EXPECT_EQ(r.stats.pose_repeated_times, 1);
  EXPECT_NEAR(r.poses[2].z.x(), 9.0, 1e-12);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("run.lcm KINCAL_POSE: event 10 repeats the time of event 5 (0.25 "
                               "s from the start) with other values (9,0,0 against 0.1,0,0)"),
            std::string::npos)
      << r.warnings[0];
  EXPECT_TRUE(ReadLcmLog(FiveOfEach(dir_), *MakeModel("unicycle").value())->warnings.empty());
}

TEST_F(LcmLog, DamagedIsReadWithWarnings) {
  // ReadLcmLog keeps the good events and reports the damage as warnings.
  const std::string path = (dir_ / "run.lcm").string();
  {
    lcm::LogFile log(path, "w");
    for (int k = 0; k < 4; ++k) {
      kincal::controls_t c{};
      c.schema_version = 1;
      c.utime = 1'000'000 + k * 100'000;
      c.model = "unicycle";
      c.num_controls = 2;
      c.names = {"v", "omega"};
      c.values = {0.5, 0.1};
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = c.utime + 50'000;
      p.valid = 1;
      PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
      PutMessage(log, "KINCAL_POSE", p, c.utime);
    }
  }
  std::ifstream in(path, std::ios::binary);
  std::string b(std::istreambuf_iterator<char>(in), {});
  in.close();
  Write("run.lcm", b.substr(0, b.size() - 5));  // the last pose cut short
  const Recording r = ReadLcmLog(path, *MakeModel("unicycle").value()).value();
  EXPECT_EQ(r.controls.size(), 4u);
  EXPECT_EQ(r.poses.size(), 3u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("cut short"), std::string::npos) << r.warnings[0];
}

}  // namespace
}  // namespace kincal
