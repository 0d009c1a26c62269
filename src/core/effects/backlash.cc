// backlash: play in the steering linkage. The realised steering s only moves once the
// command u has taken up the play of total width `backlash`:
//   u > s + backlash/2  ->  s = u - backlash/2;   u < s - backlash/2  ->  s = u + backlash/2
// Acts on the model's steering channel, in that channel's unit; s is an internal state.
// A negative width acts as zero, so the parameter has one sign and fits cannot flip it.
#include "kincal/effect.h"

namespace kincal {
namespace {

class Backlash final : public EffectImpl<Backlash> {
 public:
  std::string_view name() const override { return "backlash"; }
  std::string_view description() const override {
    return "play of width backlash in the steering linkage";
  }
  EffectStage stage() const override { return EffectStage::kControlMap; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  int num_states() const override { return 1; }
  bool time_varying() const override { return true; }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kHeading, Regressor::kSteerReversal}};
  }
  bool AppliesTo(const KinematicModel& model) const override { return model.has_steering(); }
  bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
            std::string* error) override {
    if (!channels.empty()) {
      *error = "backlash acts on the steering channel and takes no channel list";
      return false;
    }
    channel_ = model.steering_channel();
    if (channel_ < 0) {
      *error = "model '" + std::string(model.name()) + "' has no steering channel";
      return false;
    }
    const auto& ch = model.controls()[static_cast<size_t>(channel_)];
    params_ = {{"backlash", ch.unit, 0.0, ch.unit == "rad" ? 0.02 : 20.0,
                "steering reversals while driving"}};
    return true;
  }
  template <class T>
  void InitStatesT(const T*, const T* u, T* s) const {
    s[0] = u[channel_];
  }
  template <class T>
  void AdvanceT(const T* p, const T&, T* s, T* u) const {
    const T half = (ScalarOf(p[0]) >= 0.0 ? p[0] : T(0.0)) * 0.5;
    const T& cmd = u[channel_];
    if (ScalarOf(cmd) > ScalarOf(s[0] + half)) {
      s[0] = cmd - half;
    } else if (ScalarOf(cmd) < ScalarOf(s[0] - half)) {
      s[0] = cmd + half;
    }
    u[channel_] = s[0];
  }

 private:
  std::vector<ParamInfo> params_ = {{"backlash", "rad", 0.0, 0.02}};
  int channel_ = -1;
};

}  // namespace

KINCAL_EFFECT_FACTORY(Backlash)

}  // namespace kincal
