// The signature vocabulary: every regressor's name round-trips, names are sorted (reports
// list regressors in enum order, which is their names' order), unknown names are refused,
// and a RegressorValues holds only what was set.
#include "kincal/signature.h"

#include <gtest/gtest.h>

#include <string>

namespace kincal {
namespace {

TEST(Signature, EveryRegressorNameRoundTripsInSortedOrder) {
  std::string previous;
  for (int i = 0; i < kNumRegressors; ++i) {
    const auto r = static_cast<Regressor>(i);
    const std::string name(RegressorName(r));
    EXPECT_FALSE(name.empty()) << i;
    EXPECT_LT(previous, name) << "regressor " << i << " out of name order";
    EXPECT_EQ(RegressorFromName(name), r) << name;
    previous = name;
  }
  EXPECT_EQ(RegressorName(Regressor::kLatAccel), "lat_accel");
  EXPECT_EQ(RegressorName(Regressor::kYawAccel), "yaw_accel");
}

TEST(Signature, UnknownNamesAreRefused) {
  EXPECT_FALSE(RegressorFromName("").has_value());
  EXPECT_FALSE(RegressorFromName("Speed").has_value());  // names are exact
  EXPECT_FALSE(RegressorFromName("speed ").has_value());
  EXPECT_FALSE(RegressorFromName("along").has_value());  // a component, not a regressor
}

TEST(Signature, ComponentNames) {
  EXPECT_EQ(ComponentName(ResidualComponent::kAlong), "along");
  EXPECT_EQ(ComponentName(ResidualComponent::kCross), "cross");
  EXPECT_EQ(ComponentName(ResidualComponent::kHeading), "heading");
}

TEST(Signature, ValuesHoldOnlyWhatWasSet) {
  RegressorValues v;
  for (int i = 0; i < kNumRegressors; ++i) EXPECT_FALSE(v.Has(static_cast<Regressor>(i)));
  v.Set(Regressor::kTurnRate, -0.5);
  v.Set(Regressor::kYawAccel, 2.0);  // the last bit
  EXPECT_TRUE(v.Has(Regressor::kTurnRate));
  EXPECT_TRUE(v.Has(Regressor::kYawAccel));
  EXPECT_FALSE(v.Has(Regressor::kSteerReversal));
  EXPECT_EQ(v[Regressor::kTurnRate], -0.5);
  EXPECT_EQ(v[Regressor::kYawAccel], 2.0);
  v.Set(Regressor::kTurnRate, 0.25);  // set again: the new value
  EXPECT_EQ(v[Regressor::kTurnRate], 0.25);
}

}  // namespace
}  // namespace kincal
