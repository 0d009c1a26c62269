// The simulated camera (src/daemon/sim_source.cc): it renders the scenario's robot and
// publishes the robot's commands like a robot would, and its truth with every frame, a
// chunk of the run at a time with no seam in the frames or the commands.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/truth_t.hpp>

#include "daemon/daemon_test_util.h"
#include "daemon/pose_stage.h"
#include "daemon/sources.h"
#include "kincal/angles.h"
#include "source_dir.h"

namespace kincal::daemon {
namespace {

using test_util::Counted;
using test_util::Drain;
using test_util::SimConfig;
using test_util::TempPath;

TEST(SimSource, SimulatedCameraRendersTheRobotAndPublishesItsControls) {
  DaemonConfig c = SimConfig(2.0);
  Counted n;
  // The source keeps its own copy of the set-up: a temporary is fine.
  auto src =
      MakeSource(
          c, LoadVisionSetup(c).value(), [&n](const void*, size_t, int64_t) { ++n.controls; },
          [](const std::string&, const void*, size_t, int64_t) {})
          .value();
  ASSERT_NE(src, nullptr);
  EXPECT_TRUE(src->capabilities().carries_controls);
  EXPECT_TRUE(src->capabilities().lossless);  // sim.speed 0
  ASSERT_TRUE(src->Start().ok());
  Drain(src.get(), &n);
  src->Stop();
  EXPECT_NEAR(n.frames, 2.0 * 30, 2);
  EXPECT_GT(n.controls, 0);
  EXPECT_TRUE(n.in_order);
}

// The simulated run is made a chunk at a time (memory bounded by sim.chunk_s, not by the
// duration): frames and commands continue across the seams with no gap, repeat or reorder.
struct SimStream {
  std::vector<int64_t> frame_utimes, sequences, control_utimes;
};

SimStream DrainSim(double duration_s, double chunk_s) {
  DaemonConfig c = SimConfig(duration_s);
  c.sim.chunk_s = chunk_s;
  SimStream out;
  auto src = MakeSource(
                 c, LoadVisionSetup(c).value(),
                 [&out](const void* data, size_t size, int64_t) {
                   kincal::controls_t m;
                   if (m.decode(data, 0, static_cast<int>(size)) > 0)
                     out.control_utimes.push_back(m.utime);
                 },
                 [](const std::string&, const void*, size_t, int64_t) {})
                 .value();
  EXPECT_TRUE(src->Start().ok());
  Frame f;
  std::string error;
  for (SourceStatus st; (st = src->Next(&f, 1000, &error)) != SourceStatus::kEnd;) {
    if (st != SourceStatus::kFrame) continue;
    out.frame_utimes.push_back(f.utime);
    out.sequences.push_back(f.sequence);
  }
  src->Stop();
  return out;
}

std::pair<int64_t, int64_t> IntervalRange(const std::vector<int64_t>& t) {
  int64_t lo = INT64_MAX, hi = 0;
  for (size_t i = 1; i < t.size(); ++i) {
    lo = std::min(lo, t[i] - t[i - 1]);
    hi = std::max(hi, t[i] - t[i - 1]);
  }
  return {lo, hi};
}

TEST(SimSource, SimulatedRunIsMadeInChunksWithoutSeams) {
  const SimStream whole = DrainSim(4.5, 300.0);
  const SimStream chunked = DrainSim(4.5, 1.0);  // four seams
  ASSERT_GT(whole.frame_utimes.size(), 100u);
  EXPECT_NEAR(static_cast<double>(chunked.frame_utimes.size()),
              static_cast<double>(whole.frame_utimes.size()), 1.0);
  for (size_t i = 0; i < chunked.sequences.size(); ++i)
    ASSERT_EQ(chunked.sequences[i], static_cast<int64_t>(i));
  // Frame intervals across seams are the camera's own (30 fps, no jitter in this scenario).
  const auto [lo_w, hi_w] = IntervalRange(whole.frame_utimes);
  const auto [lo_c, hi_c] = IntervalRange(chunked.frame_utimes);
  EXPECT_GE(lo_c, lo_w - 1);
  EXPECT_LE(hi_c, hi_w + 1);
  // Commands: strictly later each time, at the scenario's rate, up to the last frame.
  ASSERT_GT(chunked.control_utimes.size(), 10u);
  const auto [clo, chi] = IntervalRange(chunked.control_utimes);
  const auto [wlo, whi] = IntervalRange(whole.control_utimes);
  EXPECT_GT(clo, 0);
  EXPECT_LE(chi, whi + 1);
  EXPECT_GE(chunked.control_utimes.back(), chunked.frame_utimes.back() - whi);
  (void)wlo;
}

// With every frame, the truth: the scenario's parameters and where the tracked point
// stands. The stand is checked against the pose the detector measures in that frame (the
// renderer and the pose stage, not the message's own arithmetic), to a few millimetres.
TEST(SimSource, PublishesTheTruthWithEveryFrame) {
  DaemonConfig c = SimConfig(3.0);
  std::vector<kincal::truth_t> truths;
  std::vector<std::string> channels;
  std::vector<int64_t> logged;
  auto src = MakeSource(
                 c, LoadVisionSetup(c).value(), [](const void*, size_t, int64_t) {},
                 [&](const std::string& ch, const void* data, size_t n, int64_t log_utime) {
                   if (ch != c.lcm.truth_channel) return;
                   kincal::truth_t m;
                   ASSERT_GT(m.decode(data, 0, static_cast<int>(n)), 0);
                   truths.push_back(m);
                   logged.push_back(log_utime);
                 })
                 .value();
  const VisionSetup vis = LoadVisionSetup(c).value();
  PoseStage stage(c.pose, c.detector, vis);
  ASSERT_TRUE(src->Start().ok());
  Frame f;
  PoseSample p;
  std::string error;
  int frames = 0, compared = 0;
  double worst_m = 0, worst_rad = 0;
  for (SourceStatus st; (st = src->Next(&f, 1000, &error)) != SourceStatus::kEnd;) {
    if (st != SourceStatus::kFrame) continue;
    ++frames;
    ASSERT_EQ(truths.size(), static_cast<size_t>(frames));
    const kincal::truth_t& t = truths.back();
    EXPECT_EQ(t.frame_sequence, f.sequence);
    EXPECT_EQ(t.utime, f.utime);
    EXPECT_EQ(logged.back(), f.utime);  // recorded too, at the frame's time
    ASSERT_TRUE(stage.Process(f, &p, &error)) << error;
    if (!t.on_floor || !p.valid) continue;
    ++compared;
    worst_m = std::max(worst_m, std::hypot(p.xytheta.x() - t.x, p.xytheta.y() - t.y));
    worst_rad = std::max(worst_rad, std::abs(WrapAngle(p.xytheta.z() - t.theta)));
  }
  src->Stop();
  ASSERT_GT(compared, frames / 2);
  EXPECT_LT(worst_m, 0.002);
  EXPECT_LT(worst_rad, 0.02);
  // The parameters: the scenario's truth, every one of the model's by name.
  const auto truth = test_util::Truth(c);
  const kincal::truth_t& t = truths.front();
  EXPECT_EQ(t.model, c.robot.model);
  ASSERT_EQ(t.num_params, static_cast<int>(t.names.size()));
  ASSERT_GE(truth.size(), 1u);
  for (const auto& [name, value] : truth) {
    const auto it = std::find(t.names.begin(), t.names.end(), name);
    ASSERT_NE(it, t.names.end()) << name;
    EXPECT_EQ(t.values[static_cast<size_t>(it - t.names.begin())], value) << name;
  }
}

}  // namespace
}  // namespace kincal::daemon
