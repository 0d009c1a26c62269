// Effects: what the bare kinematic model lacks.
//
// An effect adds parameters (and possibly internal states) to a model and acts at one
// stage of the chain from logged command to measured pose:
//
//   kControlTiming   which command sample is in force: u(t - delay)
//   kControlMap      command -> realised control, per channel (gain, dead band, lag...)
//   kMotion          body twist -> body twist (yaw-rate bias, lateral slip...)
//   kMeasurement     kinematic reference pose -> tracked target pose (lever arm)
//
// Effects never duplicate a parameter the bare model has (wheel radii, k_v, steer_offset
// belong to the model). The simulator and all estimators use effects only through
// `System`, so an effect written once is simulated, filtered and batch-fitted alike.
//
// Adding an effect: one file in src/core/effects/ deriving EffectImpl<Self>, overriding
// the hooks of its stage as templates, declaring its residual signature, and ending with
// `KINCAL_EFFECT_FACTORY(Self)`; then its lines in the one explicit list,
// src/core/effects/effect_list.cc, whose order is the registry's (analyze tries candidates
// in it; the online check names the first effect whose signature fits), and the file in
// CMakeLists.txt's source list.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/model.h"
#include "kincal/registry.h"
#include "kincal/signature.h"
#include "kincal/status.h"
#include "kincal/types.h"

namespace kincal {

enum class EffectStage { kControlTiming, kControlMap, kMotion, kMeasurement };
std::string_view ToString(EffectStage s);

template <typename T>
struct Pose2 {
  T x{0.0};      // m
  T y{0.0};      // m
  T theta{0.0};  // rad
};

// Binds channel-wise effects: `requested` names (empty = all channels) to indices,
// filling *channels; returns false with *error on an unknown name.
bool BindChannels(const KinematicModel& model, const std::vector<std::string>& requested,
                  std::vector<int>* channels, std::string* error);

// Options for constructing an effect: which control channels it acts on (by name; empty
// means every channel the effect supports on that model).
struct EffectSpec {
  std::string name;
  std::vector<std::string> channels;
};

class Effect {
 public:
  virtual ~Effect() = default;

  virtual std::string_view name() const = 0;
  virtual std::string_view description() const = 0;
  virtual EffectStage stage() const = 0;
  virtual const std::vector<ParamInfo>& params() const = 0;
  int num_params() const { return static_cast<int>(params().size()); }

  // Residual signature: the (component, regressor) correlations its absence leaves in the
  // prediction errors (kincal/signature.h), which `kincal analyze` and the online model
  // check look for.
  virtual std::vector<SignatureTerm> signature() const { return {}; }
  // Whether the effect makes sense on `model` (e.g. backlash needs a steering channel).
  virtual bool AppliesTo(const KinematicModel& model) const = 0;
  // Binds to a model and the requested channels. Returns false with *error set if the
  // channels are not valid for this model. Called once, before any evaluation.
  virtual bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
                    std::string* error) = 0;
  // Internal states (e.g. a lag's realised control), appended to the augmented state.
  virtual int num_states() const { return 0; }
  // True if the realised control varies within a constant-command interval (needs
  // sub-stepping during integration).
  virtual bool time_varying() const { return false; }

  // --- kControlTiming: delay (s) of the command stream, > 0 means motion follows older
  // commands.
  virtual double Delay(const double* p) const = 0;
  virtual Jet Delay(const Jet* p) const = 0;
  virtual BJet Delay(const BJet* p) const = 0;
  // --- kControlMap: maps commanded to realised controls in place (u[num_controls]).
  virtual void MapControls(const double* p, double* u) const = 0;
  virtual void MapControls(const Jet* p, Jet* u) const = 0;
  virtual void MapControls(const BJet* p, BJet* u) const = 0;
  // Steady-state internal states for a constant (mapped) control u.
  virtual void InitStates(const double* p, const double* u, double* s) const = 0;
  virtual void InitStates(const Jet* p, const Jet* u, Jet* s) const = 0;
  virtual void InitStates(const BJet* p, const BJet* u, BJet* s) const = 0;
  // Advances internal states over dt (s) towards target control u (after MapControls),
  // and replaces u by the mean realised control over the step. For a constant target the
  // states must be exact over any dt (one call over 2h equals two over h): a walk of the
  // states alone (a warm-up) takes one step per command interval when no other effect
  // has states.
  virtual void Advance(const double* p, double dt, double* s, double* u) const = 0;
  virtual void Advance(const Jet* p, const Jet& dt, Jet* s, Jet* u) const = 0;
  virtual void Advance(const BJet* p, const BJet& dt, BJet* s, BJet* u) const = 0;
  // --- kMotion: modifies the body twist given realised controls u.
  virtual void ModifyTwist(const double* p, const double* u, Twist<double>* tw) const = 0;
  virtual void ModifyTwist(const Jet* p, const Jet* u, Twist<Jet>* tw) const = 0;
  virtual void ModifyTwist(const BJet* p, const BJet* u, Twist<BJet>* tw) const = 0;
  // --- kMeasurement: maps the reference pose to the measured target pose.
  virtual void Measure(const double* p, Pose2<double>* pose) const = 0;
  virtual void Measure(const Jet* p, Pose2<Jet>* pose) const = 0;
  virtual void Measure(const BJet* p, Pose2<BJet>* pose) const = 0;
};

// CRTP adapter. Derived overrides any of these member templates (the defaults do
// nothing):
//   template <class T> T DelayT(const T* p) const;
//   template <class T> void MapControlsT(const T* p, T* u) const;
//   template <class T> void InitStatesT(const T* p, const T* u, T* s) const;
//   template <class T> void AdvanceT(const T* p, const T& dt, T* s, T* u) const;
//   template <class T> void ModifyTwistT(const T* p, const T* u, Twist<T>* tw) const;
//   template <class T> void MeasureT(const T* p, Pose2<T>* pose) const;
template <typename Derived>
class EffectImpl : public Effect {
 public:
  template <class T>
  T DelayT(const T*) const {
    return T(0.0);
  }
  template <class T>
  void MapControlsT(const T*, T*) const {}
  template <class T>
  void InitStatesT(const T*, const T*, T*) const {}
  template <class T>
  void AdvanceT(const T*, const T&, T*, T*) const {}
  template <class T>
  void ModifyTwistT(const T*, const T*, Twist<T>*) const {}
  template <class T>
  void MeasureT(const T*, Pose2<T>*) const {}

  double Delay(const double* p) const final { return self().DelayT(p); }
  Jet Delay(const Jet* p) const final { return self().DelayT(p); }
  BJet Delay(const BJet* p) const final { return self().DelayT(p); }
  void MapControls(const double* p, double* u) const final { self().MapControlsT(p, u); }
  void MapControls(const Jet* p, Jet* u) const final { self().MapControlsT(p, u); }
  void MapControls(const BJet* p, BJet* u) const final { self().MapControlsT(p, u); }
  void InitStates(const double* p, const double* u, double* s) const final {
    self().InitStatesT(p, u, s);
  }
  void InitStates(const Jet* p, const Jet* u, Jet* s) const final { self().InitStatesT(p, u, s); }
  void InitStates(const BJet* p, const BJet* u, BJet* s) const final {
    self().InitStatesT(p, u, s);
  }
  void Advance(const double* p, double dt, double* s, double* u) const final {
    self().AdvanceT(p, dt, s, u);
  }
  void Advance(const Jet* p, const Jet& dt, Jet* s, Jet* u) const final {
    self().AdvanceT(p, dt, s, u);
  }
  void Advance(const BJet* p, const BJet& dt, BJet* s, BJet* u) const final {
    self().AdvanceT(p, dt, s, u);
  }
  void ModifyTwist(const double* p, const double* u, Twist<double>* tw) const final {
    self().ModifyTwistT(p, u, tw);
  }
  void ModifyTwist(const Jet* p, const Jet* u, Twist<Jet>* tw) const final {
    self().ModifyTwistT(p, u, tw);
  }
  void ModifyTwist(const BJet* p, const BJet* u, Twist<BJet>* tw) const final {
    self().ModifyTwistT(p, u, tw);
  }
  void Measure(const double* p, Pose2<double>* pose) const final { self().MeasureT(p, pose); }
  void Measure(const Jet* p, Pose2<Jet>* pose) const final { self().MeasureT(p, pose); }
  void Measure(const BJet* p, Pose2<BJet>* pose) const final { self().MeasureT(p, pose); }

  // Default binding: accepts no channel list (effects acting on channels override).
  bool Bind(const KinematicModel&, const std::vector<std::string>& channels,
            std::string* error) override {
    if (!channels.empty()) {
      *error = std::string(name()) + " takes no channel list";
      return false;
    }
    return true;
  }
  bool AppliesTo(const KinematicModel&) const override { return true; }

 private:
  const Derived& self() const { return *static_cast<const Derived*>(this); }
};

using EffectRegistry = Registry<Effect>;
// The effects in the one explicit list, src/core/effects/effect_list.cc.
void RegisterBuiltins(Registry<Effect>* registry);

// Creates and binds an effect; an error names the effect and says why: the name is
// unknown, the effect does not apply to the model, or the channels are invalid.
Status MakeEffect(const EffectSpec& spec, const KinematicModel& model,
                  std::unique_ptr<Effect>* out);
// Parses "name" or "name[ch1,ch2]" into a spec.
Status ParseEffectSpec(std::string_view text, EffectSpec* out);

// The two as values.
StatusOr<std::unique_ptr<Effect>> MakeEffect(const EffectSpec& spec, const KinematicModel& model);
StatusOr<EffectSpec> ParseEffectSpec(std::string_view text);

}  // namespace kincal

// Ends an effect's implementation file, after its anonymous namespace, inside namespace
// kincal: the factory src/core/effects/effect_list.cc registers.
#define KINCAL_EFFECT_FACTORY(Class) \
  std::unique_ptr<Effect> New##Class##Effect() { return std::make_unique<Class>(); }
