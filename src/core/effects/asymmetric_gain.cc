// asymmetric_gain: a channel's gain differs with the sign of its command,
//   u' = u (1 + asym sign(u))
// so forward/backward (or left/right) realised rates differ by a factor
// (1 + asym) / (1 - asym). The mean gain stays the model's own parameter. One parameter
// `asym_<channel>` per channel (default: every channel).
#include "kincal/effect.h"

namespace kincal {
namespace {

class AsymmetricGain final : public EffectImpl<AsymmetricGain> {
 public:
  std::string_view name() const override { return "asymmetric_gain"; }
  std::string_view description() const override {
    return "gain of a channel differs with the sign of its command (asym_<channel>)";
  }
  EffectStage stage() const override { return EffectStage::kControlMap; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kHeading, Regressor::kAbsTurnRate},
            {ResidualComponent::kAlong, Regressor::kAbsSpeed}};
  }
  bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
            std::string* error) override {
    if (!BindChannels(model, channels, &channels_, error)) return false;
    params_.clear();
    for (int c : channels_) {
      params_.push_back({"asym_" + model.controls()[static_cast<size_t>(c)].name, "1", 0.0, 0.1,
                         "commands of both signs"});
    }
    return true;
  }
  template <class T>
  void MapControlsT(const T* p, T* u) const {
    for (size_t k = 0; k < channels_.size(); ++k) {
      T& v = u[channels_[k]];
      const double sgn = ScalarOf(v) > 0.0 ? 1.0 : (ScalarOf(v) < 0.0 ? -1.0 : 0.0);
      v = v * (1.0 + p[k] * sgn);
    }
  }

 private:
  std::vector<ParamInfo> params_;
  std::vector<int> channels_;
};

}  // namespace

KINCAL_EFFECT_FACTORY(AsymmetricGain)

}  // namespace kincal
