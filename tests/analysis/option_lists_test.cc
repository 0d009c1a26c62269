// --init and --effects lists: parsed whole or refused, naming the item.
#include "kincal/analysis/option_lists.h"

#include <gtest/gtest.h>

namespace kincal {
namespace {

TEST(OptionLists, InitValuesByName) {
  std::map<std::string, double> init;
  ASSERT_TRUE(ParseInitList("k_v=0.9,k_omega=1.1e0", &init).ok());
  EXPECT_EQ(init, (std::map<std::string, double>{{"k_v", 0.9}, {"k_omega", 1.1}}));
  ASSERT_TRUE(ParseInitList("", &init).ok());
  EXPECT_TRUE(init.empty());
  for (const char* bad : {"k_v=nan", "k_v=inf", "k_v=", "k_v", "=1", "k_v=1x", "k_v=1,k_v=2"}) {
    const Status s = ParseInitList(bad, &init);
    EXPECT_FALSE(s.ok()) << bad;
    EXPECT_NE(s.message().find("--init"), std::string::npos) << s.message();
  }
}

TEST(OptionLists, EffectsSplitOutsideBracketsAndMustParse) {
  std::vector<std::string> effects;
  ASSERT_TRUE(
      ParseEffectList("time_offset,actuator_lag[omega_l,omega_r],lever_arm", &effects).ok());
  EXPECT_EQ(effects, (std::vector<std::string>{"time_offset", "actuator_lag[omega_l,omega_r]",
                                               "lever_arm"}));
  // Reproduces issue 16 (item 13): a malformed list silently tried nothing.
  for (const char* bad : {"dead_band[v", "dead_band]v[", "a[b]]", "lag[]x"}) {
    const Status s = ParseEffectList(bad, &effects);
    EXPECT_FALSE(s.ok()) << bad;
    EXPECT_TRUE(effects.empty()) << bad;
    EXPECT_NE(s.message().find("--effects"), std::string::npos) << s.message();
  }
}

}  // namespace
}  // namespace kincal
