#include "kincal/estimation/ceres_logging.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include "kincal/estimation/batch.h"
#include "kincal/sim/simulator.h"
#include "kincal/system.h"

namespace kincal {
namespace {

// Straight-line driving does not excite the track width d: the covariance is rank
// deficient, and Ceres says so through glog. That must reach kincal's log, not stderr.
TEST(CeresLogging, RankDeficientCovarianceWarningsGoToOurLogNotStderr) {
  const System sys = MakeSystem("diffdrive").value();
  ControlSignal u(2, 0);
  const double both[2] = {10.0, 10.0};
  AppendConstant(&u, 0, SecondsToNs(5.0), both);
  std::vector<PoseMeasurement> meas;
  for (int k = 0; k <= 50; ++k) {
    const double t = 0.1 * k;
    meas.push_back({SecondsToNs(t), {0.31 * t, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-6, 0});
  }
  auto ring = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(64);
  auto previous = spdlog::default_logger();
  auto logger = std::make_shared<spdlog::logger>("capture", ring);
  logger->set_level(spdlog::level::debug);
  spdlog::set_default_logger(logger);
  ::testing::internal::CaptureStderr();
  const BatchResult r = FitBatch(sys, u, meas, Eigen::Vector3d(0.031, 0.031, 0.15), BatchOptions{});
  const std::string err = ::testing::internal::GetCapturedStderr();
  spdlog::set_default_logger(previous);
  EXPECT_TRUE(r.status.ok()) << r.status.message();
  EXPECT_NEAR(r.params[0], 0.031, 1e-4);  // the wheel radii are observed
  EXPECT_EQ(err, "");
  bool routed = false;
  for (const auto& line : ring->last_formatted()) routed |= line.find("ceres") != std::string::npos;
  EXPECT_TRUE(routed) << "Ceres said nothing about the rank-deficient covariance";
}

}  // namespace
}  // namespace kincal
