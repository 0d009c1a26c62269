// The filter's options: the defaults are valid; an unknown filter names the known ones;
// negative noise, periods and gates are refused, naming the field; the re-fit window fits
// in the control history.
#include "kincal/online/filter_options.h"

#include <gtest/gtest.h>

namespace kincal {
namespace {

TEST(FilterOptions, DefaultsAreValidAndEachBadFieldIsNamed) {
  std::string error;
  EXPECT_TRUE(FilterOptions{}.IsValid(&error)) << error;
  FilterOptions f;
  f.type = "kalman";
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_NE(error.find("filter.type: unknown filter 'kalman' (known: "), std::string::npos)
      << error;
  EXPECT_NE(error.find("dd2"), std::string::npos) << error;
  f = FilterOptions{};
  f.control_psd = {1e-4, -1e-4};
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_EQ(error, "filter.control_psd must be >= 0");
  f = FilterOptions{};
  f.pose_psd[2] = -1;
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_EQ(error, "filter.pose_psd must be >= 0");
  f = FilterOptions{};
  f.max_pose_gap_s = 0;
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_NE(error.find("max_pose_gap_s"), std::string::npos) << error;
  f = FilterOptions{};
  f.divergence_gated = 0;
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_NE(error.find("divergence_gated"), std::string::npos) << error;
  f = FilterOptions{};
  f.batch_window_s = f.control_history_s + 1;
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_EQ(error, "filter.batch_window_s must be in (0, control_history_s]");
}

}  // namespace
}  // namespace kincal
