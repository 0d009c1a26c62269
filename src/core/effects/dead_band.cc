// dead_band: commands smaller than a threshold produce no motion, larger ones are
// reduced by it:  u' = sign(u) max(|u| - band, 0). One parameter `band_<channel>` (in the
// channel's unit) per channel (default: every channel). A negative band acts as zero, so
// the parameter has one sign and fits cannot flip it.
#include "kincal/effect.h"

namespace kincal {
namespace {

class DeadBand final : public EffectImpl<DeadBand> {
 public:
  std::string_view name() const override { return "dead_band"; }
  std::string_view description() const override {
    return "commands below band_<channel> produce no motion";
  }
  EffectStage stage() const override { return EffectStage::kControlMap; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kAlong, Regressor::kSmallSpeed},
            {ResidualComponent::kHeading, Regressor::kSmallTurn}};
  }
  bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
            std::string* error) override {
    if (!BindChannels(model, channels, &channels_, error)) return false;
    params_.clear();
    for (int c : channels_) {
      const auto& ch = model.controls()[static_cast<size_t>(c)];
      params_.push_back({"band_" + ch.name, ch.unit, 0.0, 0.02, "small commands"});
    }
    return true;
  }
  template <class T>
  void MapControlsT(const T* p, T* u) const {
    for (size_t k = 0; k < channels_.size(); ++k) {
      T& v = u[channels_[k]];
      if (ScalarOf(p[k]) <= 0.0) continue;
      const double a = ScalarOf(v);
      if (std::abs(a) <= ScalarOf(p[k])) {
        v = T(0.0);
      } else {
        v = a > 0.0 ? v - p[k] : v + p[k];
      }
    }
  }

 private:
  std::vector<ParamInfo> params_;
  std::vector<int> channels_;
};

}  // namespace

KINCAL_EFFECT_FACTORY(DeadBand)

}  // namespace kincal
