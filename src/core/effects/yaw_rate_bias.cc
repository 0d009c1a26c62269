// yaw_rate_bias: a constant turn-rate error while the robot moves (a gyro-less drive
// pulling to one side). Applied only while the body is commanded to move, so a robot at
// rest stays at rest.
#include <cmath>

#include "kincal/effect.h"

namespace kincal {
namespace {

class YawRateBias final : public EffectImpl<YawRateBias> {
 public:
  std::string_view name() const override { return "yaw_rate_bias"; }
  std::string_view description() const override {
    return "constant turn-rate offset bias_rad_s while moving";
  }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kHeading, Regressor::kMoving}};
  }
  EffectStage stage() const override { return EffectStage::kMotion; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"bias_rad_s", "rad/s", 0.0, 0.05, "long stretches of motion"}};
    return kParams;
  }
  template <class T>
  void ModifyTwistT(const T* p, const T*, Twist<T>* tw) const {
    const double moving = std::abs(ScalarOf(tw->vx)) + std::abs(ScalarOf(tw->omega));
    if (moving > 1e-9) tw->omega += p[0];
  }
};

}  // namespace

KINCAL_EFFECT_FACTORY(YawRateBias)

}  // namespace kincal
