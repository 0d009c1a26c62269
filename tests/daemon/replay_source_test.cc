// The replay source (src/daemon/replay_source.cc): a log written by kincald hands over every
// frame and control in order, losslessly; a log that is missing, a directory, empty or not a
// regular file is a status naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>

#include "daemon/daemon_test_util.h"
#include "daemon/sources.h"
#include "source_dir.h"

namespace kincal::daemon {
namespace {

using test_util::Counted;
using test_util::Drain;
using test_util::SimConfig;
using test_util::TempPath;

const std::string kGoldenLog = ::kincal::testing::SourceDir() + "/tests/data/golden_replay.lcm";

TEST(ReplaySource, ReplayOfALogIsLosslessAndCarriesItsControls) {
  DaemonConfig c =
      ReadDaemonConfig(::kincal::testing::SourceDir() + "/tests/data/kincald_golden.yaml").value();
  c.source = SourceKind::kReplay;
  c.replay.path = kGoldenLog;
  c.replay.speed = 0;
  Counted n;
  auto src = MakeSource(
                 c, LoadVisionSetup(c).value(),
                 [&n](const void*, size_t, int64_t) { ++n.controls; }, nullptr)
                 .value();
  ASSERT_NE(src, nullptr);
  const SourceCapabilities caps = src->capabilities();
  EXPECT_TRUE(caps.lossless);
  EXPECT_TRUE(caps.carries_controls);
  EXPECT_TRUE(caps.controls_end_with_frames);
  EXPECT_FALSE(caps.can_reopen);
  ASSERT_TRUE(src->Start().ok());
  Drain(src.get(), &n);
  src->Stop();
  EXPECT_EQ(n.frames, 151);  // 0 to 5 s at 30 fps, as recorded
  EXPECT_GT(n.controls, 100);
  EXPECT_TRUE(n.in_order);
  EXPECT_EQ(src->rejected(), 0);
}

TEST(ReplaySource, ReplayOfAMissingLogNamesIt) {
  ReplayOptions r;
  r.path = TempPath("no_such.lcm");
  auto src = MakeReplaySource(r, LcmOptions{}, nullptr);
  const Status s = src->Start();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no_such.lcm"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("No such file or directory"), std::string::npos) << s.message();
  r.path = std::filesystem::temp_directory_path().string();
  const Status dir = MakeReplaySource(r, LcmOptions{}, nullptr)->Start();
  EXPECT_NE(dir.message().find("is a directory, expected an LCM log file"), std::string::npos)
      << dir.message();
  r.path = TempPath("empty.lcm");
  { std::ofstream touch(r.path); }
  const Status empty = MakeReplaySource(r, LcmOptions{}, nullptr)->Start();
  EXPECT_NE(empty.message().find("the log is empty (0 bytes)"), std::string::npos)
      << empty.message();
  r.path = "/dev/zero";
  const Status dev = MakeReplaySource(r, LcmOptions{}, nullptr)->Start();
  EXPECT_NE(dev.message().find("is not a regular file"), std::string::npos) << dev.message();
}

}  // namespace
}  // namespace kincal::daemon
