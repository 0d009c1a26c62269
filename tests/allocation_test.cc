// The per-frame path (predict through the control history + pose update) must not touch
// the heap: every filter uses fixed-capacity Eigen types. Counted with a replaced global
// operator new, active only inside the measured region.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include "kincal/estimation/online_calibrator.h"
#include "kincal/sim/simulator.h"

// This file replaces the global allocator with malloc/free on purpose.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace kincal {
namespace {

class NoAllocation : public ::testing::TestWithParam<const char*> {};

TEST_P(NoAllocation, FilterStepDoesNotAllocate) {
  const System sys = MakeSystem("diffdrive", {"time_offset", "actuator_lag", "lever_arm"}).value();
  std::mt19937_64 rng(5);
  ControlSignal u(2, 0);
  const std::vector<double> lo = {-5, -5}, hi = {20, 20};
  AppendSmoothRandom(&u, 0, SecondsToNs(20.0), lo, hi, 1.0, 50.0, rng);
  OnlineCalibratorOptions opt;
  opt.filter = GetParam();
  opt.noise.control_psd = {1e-3, 1e-3};
  OnlineCalibrator cal(sys, opt, 0);
  cal.controls() = u;
  VecN<kMaxState> p(sys.num_params());
  for (int i = 0; i < p.size(); ++i) p[i] = sys.params()[static_cast<size_t>(i)].default_value;
  StateMat P = StateMat::Identity(p.size(), p.size()) * 1e-6;
  const Eigen::Matrix3d R = Eigen::Matrix3d::Identity() * 1e-6;
  cal.Initialize(0, Eigen::Vector3d::Zero(), R, p, P);
  cal.AddPose(SecondsToNs(0.05), Eigen::Vector3d(0.01, 0, 0), R);  // warm-up
  g_allocations = 0;
  g_counting = true;
  for (int k = 2; k < 300; ++k) {
    cal.AddPose(SecondsToNs(0.033 * k), Eigen::Vector3d(0.01 * k, 0, 0), R);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << GetParam();
}

TEST(NoAllocationCounter, SeesAnAllocation) {
  g_allocations = 0;
  g_counting = true;
  auto* v = new std::vector<int>(10);
  g_counting = false;
  delete v;
  EXPECT_EQ(g_allocations.load(), 2);  // the vector object and its buffer
}

INSTANTIATE_TEST_SUITE_P(Filters, NoAllocation, ::testing::Values("dd2", "ekf", "ukf"));

}  // namespace
}  // namespace kincal
