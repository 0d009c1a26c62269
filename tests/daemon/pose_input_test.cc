// Logged poses into the filter's queue (src/daemon/pose_input.cc): a log without frames is
// replayed from these.
#include "daemon/pose_input.h"

#include <gtest/gtest.h>

#include <cmath>
#include <kincal/pose_t.hpp>
#include <limits>
#include <vector>

#include "lcm_round_trip.h"

namespace kincal::daemon {
namespace {

using ::kincal::testing::Encoded;

kincal::pose_t Mocap(double x, double y, double theta) {
  kincal::pose_t m{};
  m.schema_version = 1;
  m.utime = 1'000'000;
  m.x = x;
  m.y = y;
  m.theta = theta;
  m.valid = 1;  // covariance all zeros, as `kincal import` writes a PoseStamped
  return m;
}

constexpr std::array<double, 3> kSigma{0.002, 0.003, 0.01};

struct PoseFixture {
  Publisher publisher;  // not opened: nothing is published or recorded
  BoundedQueue<PoseSample> queue{16, FullPolicy::kDropOldest};
  CounterSet counters;
  PoseReceiver receiver{"KINCAL_POSE", kSigma, &publisher, &queue, &counters};
};

TEST(PoseReceiver, QueuesALoggedPoseShiftedWithTheConfiguredNoiseWhereItHasNone) {
  PoseFixture f;
  const auto buf = Encoded(Mocap(1.25, -0.5, 0.3));
  f.receiver.OnMessage(buf.data(), buf.size(), 40'000'000);
  PoseSample p;
  ASSERT_TRUE(f.queue.TryPop(p));
  EXPECT_TRUE(p.valid);
  EXPECT_EQ(p.utime, 41'000'000);
  EXPECT_EQ(p.device_utime, 0);  // none logged
  EXPECT_DOUBLE_EQ(p.xytheta.x(), 1.25);
  EXPECT_DOUBLE_EQ(p.xytheta.y(), -0.5);
  EXPECT_DOUBLE_EQ(p.xytheta.z(), 0.3);
  EXPECT_DOUBLE_EQ(p.covariance(0, 0), 0.002 * 0.002);
  EXPECT_DOUBLE_EQ(p.covariance(1, 1), 0.003 * 0.003);
  EXPECT_DOUBLE_EQ(p.covariance(2, 2), 0.01 * 0.01);
  EXPECT_DOUBLE_EQ(p.covariance(0, 1), 0.0);
  EXPECT_EQ(f.counters.poses_valid.load(), 1);
  EXPECT_EQ(f.counters.poses_published.load(), 1);
}

TEST(PoseReceiver, KeepsALoggedCovarianceThatIsOne) {
  kincal::pose_t m = Mocap(0, 0, 0);
  const double c[9] = {4e-6, 1e-6, 0, 1e-6, 9e-6, 0, 0, 0, 1e-4};
  std::copy(c, c + 9, m.covariance);
  m.source_utime = 77;
  PoseSample p;
  std::string why;
  const auto buf = Encoded(m);
  ASSERT_TRUE(DecodeLoggedPose(buf.data(), buf.size(), 5, kSigma, &p, &why)) << why;
  EXPECT_DOUBLE_EQ(p.covariance(0, 1), 1e-6);
  EXPECT_DOUBLE_EQ(p.covariance(1, 1), 9e-6);
  EXPECT_EQ(p.device_utime, 82);
  // Not symmetric, or not positive definite: the configured noise instead.
  m.covariance[1] = 2e-6;
  const auto asym = Encoded(m);
  ASSERT_TRUE(DecodeLoggedPose(asym.data(), asym.size(), 0, kSigma, &p, &why));
  EXPECT_DOUBLE_EQ(p.covariance(0, 1), 0.0);
  EXPECT_DOUBLE_EQ(p.covariance(0, 0), 0.002 * 0.002);
}

TEST(PoseReceiver, AnInvalidPoseIsQueuedAsOneWithoutTheTarget) {
  PoseFixture f;
  kincal::pose_t m = Mocap(0, 0, 0);
  m.valid = 0;
  const auto buf = Encoded(m);
  f.receiver.OnMessage(buf.data(), buf.size(), 0);
  PoseSample p;
  ASSERT_TRUE(f.queue.TryPop(p));
  EXPECT_FALSE(p.valid);
  EXPECT_EQ(f.counters.poses_invalid.load(), 1);
}

TEST(PoseReceiver, RejectsAndNamesWhatIsNotAPose) {
  PoseFixture f;
  const auto buf = Encoded(Mocap(std::numeric_limits<double>::quiet_NaN(), 0, 0));
  f.receiver.OnMessage(buf.data(), buf.size(), 0);
  EXPECT_NE(f.receiver.last_reject().find("not finite"), std::string::npos)
      << f.receiver.last_reject();
  const std::vector<uint8_t> garbage(20, 0x5a);
  f.receiver.OnMessage(garbage.data(), garbage.size(), 0);
  EXPECT_NE(f.receiver.last_reject().find("not a kincal.pose_t (20 bytes)"), std::string::npos)
      << f.receiver.last_reject();
  PoseSample p;
  EXPECT_FALSE(f.queue.TryPop(p));
  EXPECT_EQ(f.counters.frames_bad.load(), 2);
  EXPECT_EQ(f.counters.poses_valid.load(), 0);
}

}  // namespace
}  // namespace kincal::daemon
