// The generated LCM types: encode/decode round trip, and publish/subscribe through the
// in-process memq:// provider.
#include <gtest/gtest.h>

#include <kincal/controls_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <vector>

namespace kincal {
namespace {

TEST(LcmTypes, ParamsRoundTrip) {
  kincal::params_t p;
  p.schema_version = 1;
  p.utime = 123456789;
  p.model = "diffdrive";
  p.estimator = "dd2";
  p.num_params = 3;
  p.names = {"r_l", "r_r", "d"};
  p.units = {"m", "m", "m"};
  p.values = {0.031, 0.0313, 0.148};
  p.sigmas = {1e-5, 1e-5, 4e-5};
  p.covariance = {{1e-10, 0, 0}, {0, 1e-10, 0}, {0, 0, 1.6e-9}};
  p.update_count = 77;
  p.status = kincal::params_t::STATUS_CONVERGED;
  p.source = kincal::params_t::SOURCE_BATCH;
  std::vector<uint8_t> buf(static_cast<size_t>(p.getEncodedSize()));
  ASSERT_EQ(p.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  kincal::params_t q;
  ASSERT_EQ(q.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_EQ(q.names, p.names);
  EXPECT_EQ(q.values, p.values);
  EXPECT_EQ(q.covariance, p.covariance);
  EXPECT_TRUE(q.status == kincal::params_t::STATUS_CONVERGED);
  EXPECT_TRUE(q.source == kincal::params_t::SOURCE_BATCH);
  // Truncated buffers are rejected, not read past.
  EXPECT_LT(q.decode(buf.data(), 0, static_cast<int>(buf.size()) - 5), 0);
}

TEST(LcmTypes, PosePublishSubscribeOverMemq) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  struct Sink {
    std::vector<kincal::pose_t> got;
    void On(const lcm::ReceiveBuffer*, const std::string&, const kincal::pose_t* m) {
      got.push_back(*m);
    }
  } sink;
  lcm.subscribe("KINCAL_POSE", &Sink::On, &sink);
  kincal::pose_t pose{};
  pose.schema_version = 1;
  pose.utime = 42;
  pose.x = 1.5;
  pose.theta = -0.25;
  pose.covariance[0] = 1e-6;
  pose.valid = 1;
  ASSERT_EQ(lcm.publish("KINCAL_POSE", &pose), 0);
  ASSERT_GE(lcm.handleTimeout(100), 0);
  ASSERT_EQ(sink.got.size(), 1u);
  EXPECT_EQ(sink.got[0].x, 1.5);
  EXPECT_EQ(sink.got[0].theta, -0.25);
  EXPECT_EQ(sink.got[0].covariance[0], 1e-6);
}

}  // namespace
}  // namespace kincal
