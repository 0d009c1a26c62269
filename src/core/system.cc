#include "kincal/system.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "kincal/angles.h"

namespace kincal {

template <typename T>
void IntegrateArc(const Twist<T>& tw, const T& dt, T* x, T* y, T* theta) {
  using std::cos;
  using std::sin;
  const T a = tw.omega * dt;
  // s = sin(a)/omega, c = (1 - cos a)/omega, both well conditioned for small a.
  T s, c;
  if (std::abs(ScalarOf(a)) < 1e-3) {
    const T a2 = a * a;
    s = dt * (1.0 - a2 / 6.0 + a2 * a2 / 120.0);
    c = dt * a * (0.5 - a2 / 24.0 + a2 * a2 / 720.0);
  } else {
    const T half_sin = sin(a * 0.5);
    s = sin(a) / tw.omega;
    c = 2.0 * half_sin * half_sin / tw.omega;
  }
  const T dxb = s * tw.vx - c * tw.vy;
  const T dyb = c * tw.vx + s * tw.vy;
  const T ct = cos(*theta);
  const T st = sin(*theta);
  *x += ct * dxb - st * dyb;
  *y += st * dxb + ct * dyb;
  *theta += a;
}

template void IntegrateArc<double>(const Twist<double>&, const double&, double*, double*, double*);
template void IntegrateArc<Jet>(const Twist<Jet>&, const Jet&, Jet*, Jet*, Jet*);
template void IntegrateArc<BJet>(const Twist<BJet>&, const BJet&, BJet*, BJet*, BJet*);

Status System::CheckCombination(const KinematicModel& model,
                                const std::vector<std::shared_ptr<const Effect>>& effects,
                                const SystemOptions& options) {
  std::vector<std::string> names;
  int states = 0;
  for (const auto& p : model.params()) names.push_back(p.name);
  for (const auto& e : effects) {
    for (const auto& p : e->params()) {
      if (std::find(names.begin(), names.end(), p.name) != names.end()) {
        return Status::Error("parameter name '" + p.name +
                             "' appears twice (two effects of the same kind?)");
      }
      names.push_back(p.name);
    }
    states += e->num_states();
  }
  if (states > kMaxEffectStates) {
    return Status::Error(std::to_string(states) + " effect states exceed kMaxEffectStates = " +
                         std::to_string(kMaxEffectStates));
  }
  const int dim = kPoseDim + static_cast<int>(names.size()) + states;
  if (dim > kMaxState) {
    return Status::Error("augmented state of " + std::to_string(dim) +
                         " exceeds kMaxState = " + std::to_string(kMaxState));
  }
  if (!(options.max_substep_s > 0.0)) return Status::Error("max_substep_s must be > 0");
  return {};
}

System::System(std::shared_ptr<const KinematicModel> model,
               std::vector<std::shared_ptr<const Effect>> effects, SystemOptions options)
    : model_(std::move(model)), effects_(std::move(effects)), options_(options) {
  if (!model_) throw std::invalid_argument("System: null model");
  if (const Status s = CheckCombination(*model_, effects_, options_); !s.ok()) {
    throw std::invalid_argument("System: " + s.message());
  }
  params_ = model_->params();
  int offset = kPoseDim + model_->num_params();
  for (const auto& e : effects_) {
    effect_param_offset_.push_back(offset);
    offset += e->num_params();
    for (const auto& p : e->params()) params_.push_back(p);
    time_varying_ = time_varying_ || e->time_varying();
  }
  num_params_ = static_cast<int>(params_.size());
  for (const auto& e : effects_) {
    effect_state_offset_.push_back(offset);
    offset += e->num_states();
    num_effect_states_ += e->num_states();
    stateful_effects_ += e->num_states() > 0 ? 1 : 0;
  }
}

int System::ParamIndex(std::string_view name) const {
  for (size_t i = 0; i < params_.size(); ++i) {
    if (params_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::string System::StateName(int i) const {
  static const char* kPose[] = {"x", "y", "theta"};
  if (i < kPoseDim) return kPose[i];
  if (i < state_offset()) return params_[static_cast<size_t>(i - kPoseDim)].name;
  for (size_t k = 0; k < effects_.size(); ++k) {
    const int off = effect_state_offset_[k];
    if (i >= off && i < off + effects_[k]->num_states()) {
      return std::string(effects_[k]->name()) + ".s" + std::to_string(i - off);
    }
  }
  return "?";
}

StateVec System::DefaultState(double x, double y, double theta) const {
  StateVec s = StateVec::Zero(state_dim());
  s[0] = x;
  s[1] = y;
  s[2] = theta;
  for (int i = 0; i < num_params_; ++i)
    s[kPoseDim + i] = params_[static_cast<size_t>(i)].default_value;
  return s;
}

StateVec System::MakeState(double x, double y, double theta, const VecN<kMaxState>& params,
                           const ControlSignal& u, double t_s) const {
  if (params.size() != num_params_) {
    throw std::invalid_argument("System::MakeState: expected " + std::to_string(num_params_) +
                                " parameters, got " + std::to_string(params.size()));
  }
  StateVec s = StateVec::Zero(state_dim());
  s[0] = x;
  s[1] = y;
  s[2] = theta;
  s.segment(kPoseDim, num_params_) = params;
  ResetEffectStates(&s, u, t_s);
  return s;
}

template <typename T>
void System::InitEffectStates(T* x, const ControlSignal& u, double t_s) const {
  if (num_effect_states_ == 0) return;
  const double delay = ScalarOf(Delay(x));
  T uc[kMaxControls];
  const auto& values = u.At(t_s - delay);
  for (int c = 0; c < num_controls(); ++c) uc[c] = T(values[static_cast<size_t>(c)]);
  ApplyControlMap(x, uc);
  for (size_t k = 0; k < effects_.size(); ++k) {
    if (effects_[k]->num_states() == 0) continue;
    effects_[k]->InitStates(x + effect_param_offset_[k], uc, x + effect_state_offset_[k]);
  }
}

void System::SetPoseFromMeasurement(const double* z, double* x) const {
  x[0] = z[0];
  x[1] = z[1];
  x[2] = z[2];
  // Fixed-point iteration; exact after one step for a pure offset, a few for a lever arm.
  for (int it = 0; it < 4; ++it) {
    double zp[3];
    Measure(x, zp);
    x[0] += z[0] - zp[0];
    x[1] += z[1] - zp[1];
    x[2] += WrapAngle(z[2] - zp[2]);
  }
}

template <typename T>
T System::Delay(const T* x) const {
  T d(0.0);
  for (size_t k = 0; k < effects_.size(); ++k) {
    if (effects_[k]->stage() == EffectStage::kControlTiming) {
      d += effects_[k]->Delay(x + effect_param_offset_[k]);
    }
  }
  return d;
}

template <typename T>
void System::ApplyControlMap(const T* x, T* u) const {
  for (size_t k = 0; k < effects_.size(); ++k) {
    if (effects_[k]->stage() == EffectStage::kControlMap) {
      effects_[k]->MapControls(x + effect_param_offset_[k], u);
    }
  }
}

template <typename T>
Twist<T> System::RealisedTwist(const T* x, const T* u) const {
  Twist<T> tw = model_->BodyTwist(x + kPoseDim, u);
  for (size_t k = 0; k < effects_.size(); ++k) {
    if (effects_[k]->stage() == EffectStage::kMotion) {
      effects_[k]->ModifyTwist(x + effect_param_offset_[k], u, &tw);
    }
  }
  return tw;
}

template <bool kMovePose, typename T>
void System::Walk(T* x, double t0_s, double t1_s, const ControlSignal& signal, const T* v) const {
  if (!(t1_s > t0_s)) return;
  if (!kMovePose && num_effect_states_ == 0) return;
  const int nc = num_controls();
  const T delay = Delay(x);
  const double d = ScalarOf(delay);
  const int size = static_cast<int>(signal.size());
  int idx = signal.IndexAt(t0_s - d);
  T t(t0_s);
  while (true) {
    const bool last = !(idx + 1 < size && signal.TimeAt(idx + 1) + d < t1_s);
    const T seg_end = last ? T(t1_s) : T(signal.TimeAt(idx + 1)) + delay;
    const T dt = seg_end - t;
    if (ScalarOf(dt) > 0.0) {
      T u[kMaxControls];
      const auto& cmd = signal.ValuesAt(idx);
      for (int c = 0; c < nc; ++c) u[c] = T(cmd[static_cast<size_t>(c)]);
      if (v != nullptr) {
        for (int c = 0; c < nc; ++c) u[c] += v[c];
      }
      ApplyControlMap(x, u);
      if (!time_varying_) {
        if constexpr (kMovePose) {
          const Twist<T> tw = RealisedTwist(x, u);
          IntegrateArc(tw, dt, &x[0], &x[1], &x[2]);
        }
      } else {
        // Sub-steps for the pose. The states alone are exact in one step (Effect::Advance)
        // unless an effect's states follow another's sub-step means.
        const int steps =
            !kMovePose && stateful_effects_ == 1
                ? 1
                : std::max(1, static_cast<int>(std::ceil(ScalarOf(dt) / options_.max_substep_s)));
        const T h = dt / static_cast<double>(steps);
        for (int s = 0; s < steps; ++s) {
          T us[kMaxControls];
          std::copy_n(u, nc, us);
          for (size_t k = 0; k < effects_.size(); ++k) {
            if (effects_[k]->num_states() > 0) {
              effects_[k]->Advance(x + effect_param_offset_[k], h, x + effect_state_offset_[k], us);
            }
          }
          if constexpr (kMovePose) {
            const Twist<T> tw = RealisedTwist(x, us);
            IntegrateArc(tw, h, &x[0], &x[1], &x[2]);
          }
        }
      }
    }
    if (last) break;
    t = seg_end;
    ++idx;
  }
}

template <typename T>
void System::Propagate(const T* x_in, T* x_out, double t0_s, double t1_s,
                       const ControlSignal& signal, const T* v) const {
  const int n = state_dim();
  const int nc = num_controls();
  T x[kMaxState];
  std::copy_n(x_in, n, x);
  Walk<true>(x, t0_s, t1_s, signal, v);
  if (v != nullptr) {
    for (int i = 0; i < kPoseDim; ++i) x[i] += v[nc + i];
    for (int i = 0; i < num_effect_states_; ++i) x[state_offset() + i] += v[nc + kPoseDim + i];
  }
  std::copy_n(x, n, x_out);
}

template <typename T>
void System::AdvanceEffectStates(T* x, double t0_s, double t1_s, const ControlSignal& u) const {
  Walk<false>(x, t0_s, t1_s, u, static_cast<const T*>(nullptr));
}

template <typename T>
void System::Measure(const T* x, T* z) const {
  Pose2<T> pose{x[0], x[1], x[2]};
  for (size_t k = 0; k < effects_.size(); ++k) {
    if (effects_[k]->stage() == EffectStage::kMeasurement) {
      effects_[k]->Measure(x + effect_param_offset_[k], &pose);
    }
  }
  z[0] = pose.x;
  z[1] = pose.y;
  z[2] = pose.theta;
}

template void System::Propagate<double>(const double*, double*, double, double,
                                        const ControlSignal&, const double*) const;
template void System::Propagate<Jet>(const Jet*, Jet*, double, double, const ControlSignal&,
                                     const Jet*) const;
template void System::Propagate<BJet>(const BJet*, BJet*, double, double, const ControlSignal&,
                                      const BJet*) const;
template void System::Measure<BJet>(const BJet*, BJet*) const;
template void System::AdvanceEffectStates<double>(double*, double, double,
                                                  const ControlSignal&) const;
template void System::AdvanceEffectStates<Jet>(Jet*, double, double, const ControlSignal&) const;
template void System::AdvanceEffectStates<BJet>(BJet*, double, double, const ControlSignal&) const;
template void System::InitEffectStates<BJet>(BJet*, const ControlSignal&, double) const;
template BJet System::Delay<BJet>(const BJet*) const;
template void System::Measure<double>(const double*, double*) const;
template void System::Measure<Jet>(const Jet*, Jet*) const;
template void System::InitEffectStates<double>(double*, const ControlSignal&, double) const;
template void System::InitEffectStates<Jet>(Jet*, const ControlSignal&, double) const;
template double System::Delay<double>(const double*) const;
template Jet System::Delay<Jet>(const Jet*) const;

Status MakeSystem(std::string_view model, const std::vector<std::string>& effects,
                  SystemOptions options, std::unique_ptr<System>* out) {
  std::shared_ptr<const KinematicModel> m;
  if (Status s = MakeModel(model, &m); !s.ok()) return s;
  std::vector<std::shared_ptr<const Effect>> list;
  for (const auto& text : effects) {
    EffectSpec spec;
    std::unique_ptr<Effect> e;
    if (Status s = ParseEffectSpec(text, &spec); !s.ok()) return s;
    if (Status s = MakeEffect(spec, *m, &e); !s.ok()) return s;
    list.push_back(std::move(e));
  }
  if (Status s = System::CheckCombination(*m, list, options); !s.ok()) return s;
  *out = std::make_unique<System>(std::move(m), std::move(list), options);
  return {};
}

StatusOr<System> MakeSystem(std::string_view model, const std::vector<std::string>& effects,
                            SystemOptions options) {
  std::unique_ptr<System> sys;
  if (Status s = MakeSystem(model, effects, options, &sys); !s.ok()) return s;
  return std::move(*sys);
}

}  // namespace kincal
