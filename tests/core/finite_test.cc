// AllFinite (kincal/finite.h): a number, a list and a name -> number map, each with NaN,
// inf and finite values; a value that holds no number passes.
#include "kincal/finite.h"

#include <gtest/gtest.h>

#include <limits>

namespace kincal {
namespace {

TEST(Finite, NumbersListsAndMapsAreCheckedAndTheRestPass) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(AllFinite(1.5));
  EXPECT_FALSE(AllFinite(nan));
  EXPECT_FALSE(AllFinite(-inf));
  EXPECT_TRUE(AllFinite(std::vector<double>{}));
  EXPECT_TRUE(AllFinite(std::vector<double>{0.0, -1e300}));
  EXPECT_FALSE(AllFinite(std::vector<double>{0.0, inf}));
  EXPECT_TRUE(AllFinite(std::map<std::string, double>{{"r_l", 0.03}}));
  EXPECT_FALSE(AllFinite(std::map<std::string, double>{{"r_l", 0.03}, {"d", nan}}));
  EXPECT_TRUE(AllFinite(std::string("nan")));  // a name, not a number
  EXPECT_TRUE(AllFinite(true));
}

}  // namespace
}  // namespace kincal
