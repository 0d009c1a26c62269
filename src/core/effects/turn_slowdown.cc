// turn_slowdown: the robot covers less ground while it turns than the commanded speed
// says (a drive that limits wheel speeds, or scrubs in turns):
//   v_x' = v_x / (1 + c_slow |omega|)
// Found in measured data (UTIAS MR.CLAM): the along-track prediction error there
// correlates with |turn rate| far more than with anything else.
#include "kincal/effect.h"

namespace kincal {
namespace {

class TurnSlowdown final : public EffectImpl<TurnSlowdown> {
 public:
  std::string_view name() const override { return "turn_slowdown"; }
  std::string_view description() const override {
    return "forward speed lost in proportion to the turn rate (c_slow)";
  }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kAlong, Regressor::kAbsTurnRate}};
  }
  EffectStage stage() const override { return EffectStage::kMotion; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"c_slow", "s/rad", 0.0, 0.2, "driving forward while turning at several rates"}};
    return kParams;
  }
  template <class T>
  void ModifyTwistT(const T* p, const T*, Twist<T>* tw) const {
    const T abs_w = ScalarOf(tw->omega) >= 0.0 ? tw->omega : -tw->omega;
    tw->vx = tw->vx / (1.0 + p[0] * abs_w);
  }
};

}  // namespace

KINCAL_EFFECT_FACTORY(TurnSlowdown)

}  // namespace kincal
