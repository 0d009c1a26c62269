// Effect specs: parsing, binding to a model's channels, and the errors for bad ones.
#include "kincal/effect.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "kincal/estimation/filter.h"
#include "kincal/model.h"
#include "kincal/system.h"

namespace kincal {
namespace {

TEST(Effect, BadSpecsGetClearErrors) {
  const StatusOr<System> wheel = MakeSystem("unicycle", {"actuator_lag[wheel]"});
  ASSERT_FALSE(wheel.ok());
  EXPECT_NE(wheel.status().message().find("has no control 'wheel'"), std::string::npos)
      << wheel.status().message();
  EXPECT_FALSE(MakeSystem("unicycle", {"warp_drive"}).ok());
  EXPECT_FALSE(MakeSystem("hovercraft").ok());
  EXPECT_FALSE(MakeSystem("unicycle", {"lever_arm", "lever_arm"}).ok());
}

TEST(Effect, SpecsParseIntoNameAndChannels) {
  EffectSpec spec;
  ASSERT_TRUE(ParseEffectSpec("actuator_lag[omega_l,omega_r]", &spec).ok());
  EXPECT_EQ(spec.name, "actuator_lag");
  EXPECT_EQ(spec.channels, (std::vector<std::string>{"omega_l", "omega_r"}));
  ASSERT_TRUE(ParseEffectSpec("time_offset", &spec).ok());
  EXPECT_TRUE(spec.channels.empty());
  const Status bad = ParseEffectSpec("dead_band[v", &spec);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("dead_band[v"), std::string::npos) << bad.message();
}

TEST(Effect, ChannelListsGiveOneParameterPerChannel) {
  const System shared = MakeSystem("diffdrive", {"actuator_lag"}).value();
  EXPECT_EQ(shared.num_params(), 3 + 1);  // one time constant for every channel
  const System each = MakeSystem("diffdrive", {"actuator_lag[omega_l,omega_r]"}).value();
  EXPECT_EQ(each.num_params(), 3 + 2);
  EXPECT_GE(each.ParamIndex("tau_s_omega_l"), 0);
  const System asym = MakeSystem("diffdrive", {"asymmetric_gain[omega_r]"}).value();
  EXPECT_GE(asym.ParamIndex("asym_omega_r"), 0);
  EXPECT_EQ(asym.ParamIndex("asym_omega_l"), -1);
}

TEST(Effect, StatusFormNamesTheProblemWithoutThrowing) {
  std::unique_ptr<System> sys;
  const Status s = MakeSystem("unicycle", {"backlash"}, {}, &sys);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("backlash"), std::string::npos) << s.message();
  EXPECT_TRUE(MakeSystem("ackermann", {"backlash"}, {}, &sys).ok());
  EXPECT_EQ(sys->num_params(), 3 + 1);
}

// The registries' order is their explicit lists' (src/core/effects/effect_list.cc, ...),
// not the build's: analyze reports candidates and the model check names signatures in it.
TEST(Registry, OrderIsTheExplicitLists) {
  EXPECT_EQ(EffectRegistry::Instance().Names(),
            (std::vector<std::string>{"time_offset", "actuator_lag", "lever_arm", "yaw_rate_bias",
                                      "lateral_slip", "asymmetric_gain", "dead_band", "backlash",
                                      "effective_track", "turn_slowdown"}));
  EXPECT_EQ(
      ModelRegistry::Instance().Names(),
      (std::vector<std::string>{"diffdrive", "unicycle", "ackermann", "tricycle", "bicycle"}));
  EXPECT_EQ(FilterRegistry::Instance().Names(), (std::vector<std::string>{"dd2", "ekf", "ukf"}));
  EXPECT_NE(EffectRegistry::Instance().Create("lever_arm"), nullptr);
  EXPECT_EQ(EffectRegistry::Instance().Create("lever"), nullptr);
  EXPECT_EQ(FilterRegistry::Instance().Create("ukf")->name(), "ukf");
}

}  // namespace
}  // namespace kincal
