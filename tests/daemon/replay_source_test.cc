// The replay source (src/daemon/replay_source.cc): a log written by kincald hands over every
// frame and control in order, losslessly; a log without frames hands over its poses
// instead; a log that is missing, a directory, empty, not a regular file or without
// anything to replay is a status naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "daemon/daemon_test_util.h"
#include "daemon/sources.h"
#include "io/io_test_util.h"
#include "source_dir.h"

namespace kincal::daemon {
namespace {

using ::kincal::testing::PutMessage;
using test_util::Counted;
using test_util::Drain;
using test_util::SimConfig;
using test_util::TempPath;

const std::string kGoldenLog = ::kincal::testing::SourceDir() + "/tests/data/golden_replay.lcm";

// The golden log's config, replayed as fast as possible.
DaemonConfig GoldenReplay() {
  DaemonConfig c =
      ReadDaemonConfig(::kincal::testing::SourceDir() + "/tests/data/kincald_golden.yaml").value();
  c.source = SourceKind::kReplay;
  c.replay.path = kGoldenLog;
  c.replay.speed = 0;
  return c;
}

TEST(ReplaySource, ReplayOfALogIsLosslessAndCarriesItsControls) {
  const DaemonConfig c = GoldenReplay();
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

// A motion-capture log as `kincal import` writes one: controls and poses, no frames.
void WriteMocapLog(const std::string& path, int poses, bool with_controls = true) {
  lcm::LogFile out(path, "w");
  for (int k = 0; k < poses; ++k) {
    const int64_t t = 1'000'000 + 100'000 * k;
    if (with_controls) {
      kincal::controls_t u{};
      u.schema_version = 1;
      u.utime = t - 50'000;
      u.model = "unicycle";
      u.num_controls = 2;
      u.names = {"v", "omega"};
      u.values = {0.2, 0.1};
      PutMessage(out, "KINCAL_CONTROLS", u, t - 50'000);
    }
    kincal::pose_t p{};
    p.schema_version = 1;
    p.utime = t;
    p.x = 0.02 * k;
    p.valid = 1;
    PutMessage(out, "KINCAL_POSE", p, t);
    PutMessage(out, "KINCAL_HEALTH_OF_SOMETHING_ELSE", p, t);  // another channel: skipped
  }
}

struct ReplayHeard {
  std::vector<std::pair<char, int64_t>> events;  // 'c' control (receive utime), 'p' pose
};

std::unique_ptr<FrameSource> MocapSource(const std::string& path, int loops, ReplayHeard* heard) {
  ReplayOptions r;
  r.path = path;
  r.speed = 0;
  r.loops = loops;
  return MakeReplaySource(
      r, LcmOptions{},
      [heard](const void*, size_t, int64_t utime) { heard->events.emplace_back('c', utime); },
      [heard](const void* data, size_t n, int64_t shift) {
        kincal::pose_t p;
        ASSERT_GT(p.decode(data, 0, static_cast<int>(n)), 0);
        heard->events.emplace_back('p', p.utime + shift);
      });
}

TEST(ReplaySource, ALogWithoutFramesHandsOverItsPosesInOrderWithTheControls) {
  const std::string path = TempPath("mocap.lcm");
  WriteMocapLog(path, 20);
  ReplayHeard heard;
  auto src = MocapSource(path, 2, &heard);
  ASSERT_TRUE(src->Start().ok());
  Counted n;
  Drain(src.get(), &n);
  EXPECT_EQ(n.frames, 0);
  ASSERT_EQ(heard.events.size(), 80u);  // 20 controls and 20 poses, twice
  for (size_t i = 0; i < heard.events.size(); ++i) {
    EXPECT_EQ(heard.events[i].first, i % 2 == 0 ? 'c' : 'p') << i;
    if (i > 0) {
      EXPECT_GT(heard.events[i].second, heard.events[i - 1].second) << i;
    }
  }
  // The second pass is later by the log's span (0.95 s to 2.9 s) and one frame period.
  EXPECT_EQ(heard.events[41].second - heard.events[1].second, 1'950'000 + 33'333);
  EXPECT_EQ(src->rejected(), 0);
}

TEST(ReplaySource, ALogWithFramesReplaysTheFramesAndNotTheLoggedPoses) {
  const DaemonConfig c = GoldenReplay();
  int poses = 0;
  auto src = MakeSource(
                 c, LoadVisionSetup(c).value(), [](const void*, size_t, int64_t) {}, nullptr,
                 nullptr, [&poses](const void*, size_t, int64_t) { ++poses; })
                 .value();
  ASSERT_TRUE(src->Start().ok());
  Counted n;
  Drain(src.get(), &n);
  EXPECT_EQ(n.frames, 151);
  EXPECT_EQ(poses, 0);
}

TEST(ReplaySource, ALogWithNeitherFramesNorPosesIsNamed) {
  const std::string path = TempPath("controls_only.lcm");
  {
    lcm::LogFile out(path, "w");
    kincal::controls_t u{};
    u.schema_version = 1;
    u.model = "unicycle";
    u.num_controls = 0;
    PutMessage(out, "KINCAL_CONTROLS", u, 0);
  }
  ReplayHeard heard;
  const Status s = MocapSource(path, 1, &heard)->Start();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("controls_only.lcm: no frames on KINCAL_FRAME and no poses on "
                             "KINCAL_POSE: nothing to replay"),
            std::string::npos)
      << s.message();
  // Poses but no one to take them (a source made without kincald's pose intake).
  WriteMocapLog(path, 3);
  ReplayOptions r;
  r.path = path;
  const Status no_intake = MakeReplaySource(r, LcmOptions{}, nullptr)->Start();
  EXPECT_NE(no_intake.message().find("a log without frames (3 poses)"), std::string::npos)
      << no_intake.message();
}

}  // namespace
}  // namespace kincal::daemon
