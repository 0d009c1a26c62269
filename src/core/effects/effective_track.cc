// effective_track: the effective wheel separation grows with the turn rate (tyre
// scrub, caster drag), so the realised turn rate falls behind the kinematic one:
//   omega' = omega / (1 + c_track |omega|)
// On a differential drive this is D_eff = D (1 + c_track |omega|); on other models it is
// the same turn-rate dependent loss of turning.
#include "kincal/effect.h"

namespace kincal {
namespace {

class EffectiveTrack final : public EffectImpl<EffectiveTrack> {
 public:
  std::string_view name() const override { return "effective_track"; }
  std::string_view description() const override {
    return "turn-rate dependent effective wheel separation (c_track)";
  }
  EffectStage stage() const override { return EffectStage::kMotion; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"c_track", "s/rad", 0.0, 0.1, "turns at several different turn rates"}};
    return kParams;
  }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kHeading, Regressor::kTurnRateSq}};
  }
  template <class T>
  void ModifyTwistT(const T* p, const T*, Twist<T>* tw) const {
    const T abs_w = ScalarOf(tw->omega) >= 0.0 ? tw->omega : -tw->omega;
    tw->omega = tw->omega / (1.0 + p[0] * abs_w);
  }
};

}  // namespace

KINCAL_EFFECT_FACTORY(EffectiveTrack)

}  // namespace kincal
