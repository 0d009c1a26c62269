// CalibrationStore: everything below capacity; thinned evenly over the whole run when
// full, with memory fixed by the options over a six-hour run; the controls in force at
// every kept pose are the ones the robot had; gaps left by thinning and by a new time base
// are too long for a prediction window to cross.
#include "kincal/online/calibration_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace kincal {
namespace {

constexpr TimeNs kOrigin = 1'700'000'000'000'000'000;

// A control value that changes every sample (so a wrong hold shows).
std::array<double, 2> ControlAt(int64_t i) {
  return {0.1 * std::sin(1e-3 * static_cast<double>(i)), static_cast<double>(i % 997)};
}

// `seconds` of poses at pose_hz and controls at control_hz, from `start` (pipeline ns).
void FeedStore(CalibrationStore* store, TimeNs start, double seconds, double pose_hz,
               double control_hz, ControlSignal* all_controls = nullptr) {
  const auto pose_dt = static_cast<TimeNs>(1e9 / pose_hz);
  const auto control_dt = static_cast<TimeNs>(1e9 / control_hz);
  const TimeNs end = start + SecondsToNs(seconds);
  TimeNs tc = start, tp = start + pose_dt / 2;
  int64_t ic = 0, ip = 0;
  while (tc < end || tp < end) {
    if (tc <= tp && tc < end) {
      const auto v = ControlAt(ic++);
      ASSERT_TRUE(store->AddControl(tc, v));
      if (all_controls != nullptr) all_controls->Append(tc, v);
      tc += control_dt;
    } else {
      ASSERT_TRUE(store->AddPose(tp, Eigen::Vector3d(static_cast<double>(ip++), 0, 0)));
      tp += pose_dt;
    }
  }
}

TEST(CalibrationStore, KeepsEverythingBelowCapacity) {
  CalibrationStore store(CalibrationStoreOptions{}, 2);
  FeedStore(&store, kOrigin, 60.0, 30.0, 50.0);
  EXPECT_EQ(store.num_poses(), 1800u);
  EXPECT_EQ(store.num_controls(), 3000u);
  EXPECT_EQ(store.level(), 0);
  EXPECT_EQ(store.poses_thinned(), 0);
  const Recording rec = store.Snapshot(kOrigin + SecondsToNs(30.0), "test");
  EXPECT_EQ(rec.poses.size(), 900u);  // up to the time asked, not beyond
  EXPECT_LE(rec.controls.ToNs(rec.controls.TimeAt(static_cast<int>(rec.controls.size()) - 1)),
            kOrigin + SecondsToNs(30.0));
  EXPECT_EQ(rec.controls.num_channels(), 2);
}

TEST(CalibrationStore, RefusesSamplesOutOfOrder) {
  CalibrationStore store(CalibrationStoreOptions{}, 2);
  const std::array<double, 2> v{1, 2};
  ASSERT_TRUE(store.AddControl(kOrigin + 100, v));
  EXPECT_FALSE(store.AddControl(kOrigin + 50, v));
  ASSERT_TRUE(store.AddPose(kOrigin + 100, Eigen::Vector3d::Zero()));
  EXPECT_FALSE(store.AddPose(kOrigin + 100, Eigen::Vector3d::Zero()));  // repeated
  EXPECT_EQ(store.num_poses(), 1u);
  EXPECT_EQ(store.num_controls(), 1u);
}

// Six simulated hours at 30 Hz poses and 100 Hz controls into the default store (one hour
// of each): the memory it holds never grows past what the options state, the run stays
// evenly covered from its first hour to its last, and every kept pose sees the control
// the robot had at that moment.
TEST(CalibrationStore, SixHoursStayWithinTheStatedMemoryAndCoverTheRunEvenly) {
  const CalibrationStoreOptions o;
  CalibrationStore store(o, 2);
  const size_t stated = CalibrationStore::MemoryBytes(o);
  EXPECT_EQ(store.AllocatedBytes(), stated);
  EXPECT_LT(stated, 30u << 20);  // as docs/daemon.md says: under 30 MiB
  ControlSignal truth(2, kOrigin);
  FeedStore(&store, kOrigin, 6 * 3600.0, 30.0, 100.0, &truth);
  EXPECT_EQ(store.AllocatedBytes(), stated);  // never reallocated
  EXPECT_LE(store.num_poses(), static_cast<size_t>(o.max_poses));
  EXPECT_LE(store.num_controls(), static_cast<size_t>(o.max_controls));
  EXPECT_GE(store.level(), 3);  // 648,000 poses into 108,000
  EXPECT_EQ(store.poses_thinned() + static_cast<int64_t>(store.num_poses()), 6 * 3600 * 30);

  const Recording rec = store.Snapshot(kOrigin + SecondsToNs(7 * 3600.0), "test");
  ASSERT_GT(rec.poses.size(), static_cast<size_t>(o.max_poses) / 4);
  std::array<int, 6> per_hour{};
  for (const auto& p : rec.poses) {
    ++per_hour[static_cast<size_t>(std::min<int64_t>(5, (p.t_ns - kOrigin) / SecondsToNs(3600)))];
  }
  for (int h = 0; h < 6; ++h) {
    EXPECT_NEAR(per_hour[static_cast<size_t>(h)], rec.poses.size() / 6.0, 0.1 * rec.poses.size())
        << "hour " << h;
  }
  // Between consecutive kept poses: one frame interval, or a dropped block (too long for a
  // prediction window to cross).
  for (size_t i = 1; i < rec.poses.size(); ++i) {
    const double gap = NsToSeconds(rec.poses[i].t_ns - rec.poses[i - 1].t_ns);
    EXPECT_TRUE(gap < 0.04 || gap >= o.block_s - 0.04) << "gap " << gap << " s at pose " << i;
  }
  for (size_t i = 0; i < rec.poses.size(); i += 97) {
    const auto& want = truth.At(truth.ToSeconds(rec.poses[i].t_ns));
    const auto& got = rec.controls.At(rec.controls.ToSeconds(rec.poses[i].t_ns));
    ASSERT_EQ(want[0], got[0]) << "pose " << i;
    ASSERT_EQ(want[1], got[1]) << "pose " << i;
  }
}

// A clock that jumps back: the next samples are stored after the stored ones, with a gap
// longer than any prediction window, and the snapshot is one ordered recording.
TEST(CalibrationStore, ANewTimeBaseGoesOnAfterTheStoredData) {
  CalibrationStore store(CalibrationStoreOptions{}, 2);
  FeedStore(&store, kOrigin, 20.0, 30.0, 50.0);
  store.NewBase();
  FeedStore(&store, kOrigin - SecondsToNs(3600.0), 20.0, 30.0, 50.0);  // an hour back
  EXPECT_EQ(store.num_poses(), 1200u);
  const Recording rec = store.Snapshot(kOrigin - SecondsToNs(3600.0) + SecondsToNs(20.0), "t");
  ASSERT_EQ(rec.poses.size(), 1200u);
  double largest = 0;
  for (size_t i = 1; i < rec.poses.size(); ++i) {
    ASSERT_GT(rec.poses[i].t_ns, rec.poses[i - 1].t_ns);
    largest = std::max(largest, NsToSeconds(rec.poses[i].t_ns - rec.poses[i - 1].t_ns));
  }
  EXPECT_GE(largest, NsToSeconds(CalibrationStore::kBaseGapNs));
}

TEST(CalibrationStore, OptionsAreChecked) {
  std::string error;
  CalibrationStoreOptions o;
  EXPECT_TRUE(o.IsValid(&error));
  o.max_poses = 10;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_poses"), std::string::npos);
  o = CalibrationStoreOptions{};
  o.block_s = 0.1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("block_s"), std::string::npos);
}

}  // namespace
}  // namespace kincal
