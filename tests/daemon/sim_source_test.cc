// The simulated camera (src/daemon/sim_source.cc): it renders the scenario's robot and
// publishes the robot's commands like a robot would, a chunk of the run at a time with no
// seam in the frames or the commands.
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

TEST(SimSource, SimulatedCameraRendersTheRobotAndPublishesItsControls) {
  DaemonConfig c = SimConfig(2.0);
  Counted n;
  // The source keeps its own copy of the set-up: a temporary is fine.
  auto src =
      MakeSource(
          c, LoadVisionSetup(c).value(), [&n](const void*, size_t, int64_t) { ++n.controls; },
          [](const std::string&, const void*, size_t) {})
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
                 [](const std::string&, const void*, size_t) {})
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

}  // namespace
}  // namespace kincal::daemon
