#include "kincal/control_signal.h"

#include <gtest/gtest.h>

namespace kincal {
namespace {

TEST(ControlSignal, ZeroOrderHoldForwardAndZeroBeforeFirstSample) {
  ControlSignal s(2, 1'000'000'000);
  const std::array<double, 2> a = {1.0, 2.0}, b = {3.0, 4.0};
  ASSERT_TRUE(s.Append(2'000'000'000, a));
  ASSERT_TRUE(s.Append(3'000'000'000, b));
  EXPECT_EQ(s.At(0.5)[0], 0.0);  // before the first sample (t = 1.5 s)
  EXPECT_EQ(s.At(1.0)[0], 1.0);  // exactly at a sample: that sample
  EXPECT_EQ(s.At(1.999)[1], 2.0);
  EXPECT_EQ(s.At(2.0)[1], 4.0);
  EXPECT_EQ(s.At(100.0)[0], 3.0);  // held after the last sample
}

TEST(ControlSignal, RepeatedTimeReplacesAndOlderIsRejected) {
  ControlSignal s(1, 0);
  const std::array<double, 1> a = {1.0}, b = {2.0}, c = {3.0};
  ASSERT_TRUE(s.Append(10, a));
  ASSERT_TRUE(s.Append(10, b));
  EXPECT_EQ(s.size(), 1u);
  EXPECT_EQ(s.At(1.0)[0], 2.0);
  EXPECT_FALSE(s.Append(5, c));
  EXPECT_EQ(s.size(), 1u);
}

TEST(ControlSignal, DiscardBeforeKeepsSampleInForce) {
  ControlSignal s(1, 0);
  for (int i = 0; i < 10; ++i) {
    const std::array<double, 1> v = {static_cast<double>(i)};
    s.Append(SecondsToNs(i), v);
  }
  s.DiscardBefore(4.5);
  EXPECT_EQ(s.size(), 6u);
  EXPECT_EQ(s.At(4.5)[0], 4.0);
  EXPECT_EQ(s.At(9.5)[0], 9.0);
}

}  // namespace
}  // namespace kincal
