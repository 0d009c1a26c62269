// lateral_slip: the body slides sideways in proportion to the lateral (centripetal)
// acceleration v * omega:  v_y = -c_slip * v_x * omega  (outward of the turn for c > 0).
#include "kincal/effect.h"

namespace kincal {
namespace {

class LateralSlip final : public EffectImpl<LateralSlip> {
 public:
  std::string_view name() const override { return "lateral_slip"; }
  std::string_view description() const override {
    return "sideways slip velocity proportional to lateral acceleration";
  }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kCross, Regressor::kLatAccel}};
  }
  EffectStage stage() const override { return EffectStage::kMotion; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {{"c_slip", "s", 0.0, 0.02, "fast, tight turns"}};
    return kParams;
  }
  template <class T>
  void ModifyTwistT(const T* p, const T*, Twist<T>* tw) const {
    tw->vy -= p[0] * tw->vx * tw->omega;
  }
};

}  // namespace

KINCAL_EFFECT_FACTORY(LateralSlip)

}  // namespace kincal
