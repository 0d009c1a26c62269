// System: a kinematic model plus effects, as one augmented-state process.
//
// Augmented state layout (thesis 3.5, extended with effects):
//   [ x  y  theta | model params | effect params (in effect order) | effect states ]
// Parameters have zero dynamics; effect states (e.g. a lag's realised control) evolve.
//
// Process-noise input v (all optional, length noise_dim()):
//   v[0..nc)   constant perturbation of each commanded control over the step
//              (control units); a white control noise of PSD q gives std sqrt(q / dt)
//   v[nc..nc+3) additive pose perturbation at the end of the step (m, m, rad)
//   v[nc+3..)  additive perturbation of each effect state at the end of the step
// Measurement: the tracked target pose (x, y, theta); heading is an angle (wrapped).
//
// Propagation is exact between control samples for constant realised controls (SE(2)
// arc of a constant twist), and sub-stepped with a fixed maximum step where an effect
// makes the realised control time-varying within a command interval.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/effect.h"
#include "kincal/model.h"
#include "kincal/status.h"
#include "kincal/types.h"

namespace kincal {

struct SystemOptions {
  // Maximum integration step (s) when an effect varies the realised control.
  double max_substep_s = 0.005;
};

class System {
 public:
  // Throws std::invalid_argument when CheckCombination fails (callers with outside input
  // check first, or use MakeSystem's Status form).
  System(std::shared_ptr<const KinematicModel> model,
         std::vector<std::shared_ptr<const Effect>> effects = {}, SystemOptions options = {});
  // Whether the effects combine with the model: no parameter name twice (two effects of
  // the same kind), the augmented state within kMaxState, valid options.
  static Status CheckCombination(const KinematicModel& model,
                                 const std::vector<std::shared_ptr<const Effect>>& effects,
                                 const SystemOptions& options);

  const KinematicModel& model() const { return *model_; }
  const std::shared_ptr<const KinematicModel>& model_ptr() const { return model_; }
  const std::vector<std::shared_ptr<const Effect>>& effects() const { return effects_; }

  static constexpr int kPoseDim = ::kincal::kPoseDim;  // x, y, theta (kincal/types.h)
  int num_model_params() const { return model_->num_params(); }
  // Model + effect parameters.
  int num_params() const { return num_params_; }
  int num_states() const { return num_effect_states_; }
  int state_dim() const { return kPoseDim + num_params_ + num_effect_states_; }
  int noise_dim() const { return model_->num_controls() + kPoseDim + num_effect_states_; }
  int num_controls() const { return model_->num_controls(); }
  // Offset of the parameter block and of the effect-state block in the augmented state.
  int param_offset() const { return kPoseDim; }
  int state_offset() const { return kPoseDim + num_params_; }

  // Names/units/defaults of all parameters (model first, then effects).
  const std::vector<ParamInfo>& params() const { return params_; }
  int ParamIndex(std::string_view name) const;  // -1 if absent
  // Name of augmented-state element i ("x", "y", "theta", params, "<effect>.s<k>").
  std::string StateName(int i) const;
  bool IsAngle(int i) const { return i == 2; }

  // Default augmented state at a pose: default params, effect states at rest.
  StateVec DefaultState(double x, double y, double theta) const;
  // Augmented state from pose and parameter vector; effect states set to steady state for
  // the controls in force at t_s.
  StateVec MakeState(double x, double y, double theta, const VecN<kMaxState>& params,
                     const ControlSignal& u, double t_s) const;
  // Re-initialises the effect states of x to steady state for the controls at t_s.
  void ResetEffectStates(StateVec* x, const ControlSignal& u, double t_s) const {
    InitEffectStates(x->data(), u, t_s);
  }
  template <typename T>
  void InitEffectStates(T* x, const ControlSignal& u, double t_s) const;
  // Sets the reference pose x[0..3) so that Measure(x) equals the measured target pose z
  // at the parameters in x (inverts a lever arm).
  void SetPoseFromMeasurement(const double* z, double* x) const;

  // x_out = f(x_in, v) from t0 to t1 (seconds rel. the signal origin). v may be null.
  // x_in and x_out may alias.
  template <typename T>
  void Propagate(const T* x_in, T* x_out, double t0_s, double t1_s, const ControlSignal& u,
                 const T* v) const;
  // Only the effect states of x from t0 to t1 as Propagate moves them (they do not depend
  // on the pose; one step per command interval when one effect has states, to rounding);
  // the pose is left as it is. For warming a lag up through a command history whose
  // motion is not wanted.
  template <typename T>
  void AdvanceEffectStates(T* x, double t0_s, double t1_s, const ControlSignal& u) const;
  // Measured target pose z[3] of augmented state x.
  template <typename T>
  void Measure(const T* x, T* z) const;

  // Total delay applied by timing-stage effects at state x.
  template <typename T>
  T Delay(const T* x) const;

 private:
  template <typename T>
  void ApplyControlMap(const T* x, T* u) const;
  template <typename T>
  Twist<T> RealisedTwist(const T* x, const T* u) const;
  // Propagate's walk over the command intervals; the pose moves only when kMovePose.
  template <bool kMovePose, typename T>
  void Walk(T* x, double t0_s, double t1_s, const ControlSignal& signal, const T* v) const;

  std::shared_ptr<const KinematicModel> model_;
  std::vector<std::shared_ptr<const Effect>> effects_;
  SystemOptions options_;
  std::vector<ParamInfo> params_;
  std::vector<int> effect_param_offset_;  // index into state vector
  std::vector<int> effect_state_offset_;  // index into state vector
  int num_params_ = 0;
  int num_effect_states_ = 0;
  int stateful_effects_ = 0;  // effects with states
  bool time_varying_ = false;
};

// Integrates a constant body twist over dt from pose (x, y, theta), exactly (SE(2) arc).
template <typename T>
void IntegrateArc(const Twist<T>& tw, const T& dt, T* x, T* y, T* theta);

// Builds a system from a model name and effect specs ("time_offset", "actuator_lag[v]");
// an error names the unknown model or effect, the bad spec or the conflict.
Status MakeSystem(std::string_view model, const std::vector<std::string>& effects,
                  SystemOptions options, std::unique_ptr<System>* out);
// The same as a value: MakeSystem("diffdrive", {"actuator_lag"}).value() where the names
// are known good (a literal, a validated config).
StatusOr<System> MakeSystem(std::string_view model, const std::vector<std::string>& effects = {},
                            SystemOptions options = {});

}  // namespace kincal
