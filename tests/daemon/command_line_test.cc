// kincald's command line over its configuration: each option lands in its field, the
// configuration's value stands where nothing was given, and contradictions and bad values
// are errors naming the option.
#include "kincal/daemon/command_line.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace kincal::daemon {
namespace {

TEST(CommandLine, NothingGivenLeavesTheConfiguration) {
  DaemonConfig c;
  c.sim.speed = 2.5;
  c.record.path = "keep.lcm";
  const DaemonConfig before = c;
  ASSERT_TRUE(ApplyCommandLine(CommandLineOptions{}, &c).ok());
  EXPECT_EQ(c.source, before.source);
  EXPECT_EQ(c.sim.speed, 2.5);
  EXPECT_EQ(c.record.path, "keep.lcm");
  EXPECT_EQ(c.robot.effects, before.robot.effects);
}

TEST(CommandLine, SourcesAndTheirPace) {
  DaemonConfig c;
  CommandLineOptions o;
  o.replay = "run.lcm";
  o.fast = true;
  o.loops = 3;
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.source, SourceKind::kReplay);
  EXPECT_EQ(c.replay.path, "run.lcm");
  EXPECT_EQ(c.replay.speed, 0.0);  // --fast: lossless, as fast as possible
  EXPECT_EQ(c.replay.loops, 3);
  c = DaemonConfig{};
  o = CommandLineOptions{};
  o.speed = 4.0;  // the simulation (the default source) paced 4x
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.source, SourceKind::kSim);
  EXPECT_EQ(c.sim.speed, 4.0);
  o = CommandLineOptions{};
  o.libcamera = "first";
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.source, SourceKind::kLibcamera);
  EXPECT_EQ(c.libcamera.camera, "");  // the first camera libcamera lists
  o = CommandLineOptions{};
  o.device = "/dev/video2";
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.source, SourceKind::kV4l2);
  EXPECT_EQ(c.v4l2.device, "/dev/video2");
}

TEST(CommandLine, EffectsAutoNoneAndLists) {
  DaemonConfig c;
  CommandLineOptions o;
  o.effects = "time_offset,auto";
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_TRUE(c.robot.auto_effects);
  EXPECT_EQ(c.robot.effects, std::vector<std::string>{"time_offset"});
  o.effects = "none";
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_FALSE(c.robot.auto_effects);
  EXPECT_TRUE(c.robot.effects.empty());
  o.effects = "actuator_lag[v,omega";
  const Status s = ApplyCommandLine(o, &c);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("--effects"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("unbalanced brackets"), std::string::npos) << s.message();
}

TEST(CommandLine, OutputsAndCheckpoints) {
  const std::string ck = (std::filesystem::temp_directory_path() /
                          ("kincal_cl_" + std::to_string(::getpid()) + ".json"))
                             .string();
  std::filesystem::remove(ck);
  DaemonConfig c;
  CommandLineOptions o;
  o.record = "out.lcm";
  o.record_png = true;
  o.publish_frames = true;
  o.preview = true;
  o.lcm_url = "memq://";
  o.checkpoint = ck;
  o.resume_if_present = true;
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.record.path, "out.lcm");
  EXPECT_EQ(c.record.frame_encoding, FrameEncoding::kPng);
  EXPECT_TRUE(c.lcm.publish_frames);
  EXPECT_TRUE(c.preview.enabled);
  EXPECT_EQ(c.lcm.url, "memq://");
  EXPECT_EQ(c.checkpoint.path, ck);
  EXPECT_TRUE(c.checkpoint.resume.empty()) << "no checkpoint yet: a fresh start";
  std::ofstream(ck) << "{}";
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.checkpoint.resume, ck) << "a service restarted: it resumes";
  std::filesystem::remove(ck);
}

TEST(CommandLine, ContradictionsAndBadValuesNameTheOption) {
  DaemonConfig c;
  CommandLineOptions o;
  o.fast = true;
  o.speed = 2.0;
  EXPECT_EQ(ApplyCommandLine(o, &c).message(), "--speed and --fast exclude each other");
  o = CommandLineOptions{};
  o.device = "/dev/video0";
  o.replay = "run.lcm";
  EXPECT_EQ(ApplyCommandLine(o, &c).message(),
            "--device, --libcamera and --replay exclude each other");
  o = CommandLineOptions{};
  o.duration = -5.0;
  EXPECT_EQ(ApplyCommandLine(o, &c).message(),
            "--duration: expected seconds > 0 and at most 2592000 (30 days)");
  o.duration = 60.0;
  ASSERT_TRUE(ApplyCommandLine(o, &c).ok());
  EXPECT_EQ(c.sim.duration_s, 60.0);
  o = CommandLineOptions{};
  o.loops = 0;
  EXPECT_EQ(ApplyCommandLine(o, &c).message(), "--loop: expected a count >= 1");
}

}  // namespace
}  // namespace kincal::daemon
