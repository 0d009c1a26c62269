// actuator_lag: first-order lag between command and realised control.
//   du_r/dt = (u_cmd - u_r) / tau
// `actuator_lag` lags every channel with one shared time constant `tau_s`;
// `actuator_lag[a,b]` gives each listed channel its own `tau_s_<channel>`.
// The realised controls are internal states; over a step of length h with constant
// command they follow the exact exponential, and the motion uses their mean over the step.
#include <cmath>

#include "kincal/effect.h"

namespace kincal {
namespace {

constexpr const char* kHint = "changes of command: starts, stops, accelerations";

class ActuatorLag final : public EffectImpl<ActuatorLag> {
 public:
  ActuatorLag() : params_{{"tau_s", "s", 0.1, 0.1, kHint, 0.0}} {}
  std::string_view name() const override { return "actuator_lag"; }
  std::string_view description() const override {
    return "first-order lag tau_s between commanded and realised control";
  }
  EffectStage stage() const override { return EffectStage::kControlMap; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  int num_states() const override { return static_cast<int>(channels_.size()); }
  bool time_varying() const override { return true; }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kAlong, Regressor::kAccel},
            {ResidualComponent::kHeading, Regressor::kYawAccel}};
  }

  bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
            std::string* error) override {
    if (!BindChannels(model, channels, &channels_, error)) return false;
    shared_ = channels.empty();
    params_.clear();
    if (shared_) {
      params_.push_back({"tau_s", "s", 0.1, 0.1, kHint, 0.0});
    } else {
      for (int c : channels_) {
        params_.push_back(
            {"tau_s_" + model.controls()[static_cast<size_t>(c)].name, "s", 0.1, 0.1, kHint, 0.0});
      }
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
    for (size_t k = 0; k < channels_.size(); ++k) {
      const T& raw = p[shared_ ? 0 : k];
      // |tau| guarded away from zero: tau -> 0 is "no lag".
      const T tau = raw * raw < 1e-12 ? T(1e-6) : (raw < 0.0 ? -raw : raw);
      const T decay = exp(-dt / tau);
      const T mean_factor = tau / dt * (1.0 - decay);  // mean of exp(-t/tau) over [0, dt]
      const int c = channels_[k];
      const T target = u[c];
      const T diff = s[k] - target;
      u[c] = target + diff * mean_factor;
      s[k] = target + diff * decay;
    }
  }

 private:
  std::vector<ParamInfo> params_;
  std::vector<int> channels_;
  bool shared_ = true;
};

}  // namespace

KINCAL_EFFECT_FACTORY(ActuatorLag)

}  // namespace kincal
