// actuator_lag: first-order lag between command and realised control on the selected
// channels (default: all of them):
//   du_r/dt = (u_cmd - u_r) / tau_s
// The realised controls are internal states; over a step of length h with constant
// command they follow the exact exponential, and the motion uses their mean over the step.
#include <cmath>

#include "kincal/effect.h"

namespace kincal {
namespace {

class ActuatorLag final : public EffectImpl<ActuatorLag> {
 public:
  std::string_view name() const override { return "actuator_lag"; }
  std::string_view description() const override {
    return "first-order lag tau_s between commanded and realised control";
  }
  EffectStage stage() const override { return EffectStage::kControlMap; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {{"tau_s", "s", 0.1, 0.1}};
    return kParams;
  }
  int num_states() const override { return static_cast<int>(channels_.size()); }
  bool time_varying() const override { return true; }

  bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
            std::string* error) override {
    channels_.clear();
    if (channels.empty()) {
      for (int c = 0; c < model.num_controls(); ++c) channels_.push_back(c);
      return true;
    }
    for (const auto& ch : channels) {
      const int idx = model.ControlIndex(ch);
      if (idx < 0) {
        *error = "model '" + std::string(model.name()) + "' has no control '" + ch + "'";
        return false;
      }
      channels_.push_back(idx);
    }
    return true;
  }

  template <class T>
  void InitStatesT(const T*, const T* u, T* s) const {
    for (size_t k = 0; k < channels_.size(); ++k) s[k] = u[channels_[k]];
  }
  template <class T>
  void AdvanceT(const T* p, const T& dt, T* s, T* u) const {
    using std::exp;
    // Guard the time constant away from zero: tau -> 0 is "no lag".
    const T tau = p[0] * p[0] < 1e-12 ? T(1e-6) : (p[0] < 0.0 ? -p[0] : p[0]);
    const T decay = exp(-dt / tau);
    const T mean_factor = tau / dt * (1.0 - decay);  // mean of exp(-t/tau) over [0, dt]
    for (size_t k = 0; k < channels_.size(); ++k) {
      const int c = channels_[k];
      const T target = u[c];
      const T diff = s[k] - target;
      u[c] = target + diff * mean_factor;
      s[k] = target + diff * decay;
    }
  }

 private:
  std::vector<int> channels_;
};

KINCAL_REGISTER_EFFECT(ActuatorLag)

}  // namespace
}  // namespace kincal
