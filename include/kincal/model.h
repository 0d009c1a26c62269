// Kinematic models of wheeled robots.
//
// A model maps its parameters and (effective) control values to the body twist of the
// robot's kinematic reference point: forward speed v_x (m/s), lateral speed v_y (m/s,
// +left) and turn rate omega (rad/s, counter-clockwise). Pose integration, control
// timing and all unmodelled effects are handled by `System`, so a model is only this
// map plus its metadata. Every model is evaluated for double and for the autodiff Jet
// (EKF Jacobians, Ceres batch), which `ModelImpl` wires up from one template.
//
// Adding a model: one file in src/core/models/ with a class deriving ModelImpl<Self>,
// ending with `KINCAL_MODEL_FACTORY(Self)`; its lines in the one explicit list,
// src/core/models/model_list.cc (whose order is the registry's), and the file in
// CMakeLists.txt's source list. Nothing else changes.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/registry.h"
#include "kincal/status.h"
#include "kincal/types.h"

namespace kincal {

template <typename T>
struct Twist {
  T vx{0.0};     // m/s, forward, body frame
  T vy{0.0};     // m/s, left, body frame
  T omega{0.0};  // rad/s, counter-clockwise
};

class KinematicModel {
 public:
  virtual ~KinematicModel() = default;

  virtual std::string_view name() const = 0;
  virtual std::string_view description() const = 0;
  // Parameters, in the order they appear in the state vector.
  virtual const std::vector<ParamInfo>& params() const = 0;
  // Control channels, in the order of ControlSignal values.
  virtual const std::vector<ControlInfo>& controls() const = 0;
  // True for models with a steering channel (effects such as backlash need it).
  virtual bool has_steering() const { return false; }
  // Index of the steering channel, -1 if none.
  virtual int steering_channel() const { return -1; }

  int num_params() const { return static_cast<int>(params().size()); }
  int num_controls() const { return static_cast<int>(controls().size()); }
  // Index of a parameter or control by name, -1 if absent.
  int ParamIndex(std::string_view n) const;
  int ControlIndex(std::string_view n) const;

  // Body twist at parameters p[num_params()] and controls u[num_controls()].
  virtual Twist<double> BodyTwist(const double* p, const double* u) const = 0;
  virtual Twist<Jet> BodyTwist(const Jet* p, const Jet* u) const = 0;
  virtual Twist<BJet> BodyTwist(const BJet* p, const BJet* u) const = 0;
};

// CRTP adapter: Derived provides
//   template <typename T> Twist<T> Eval(const T* p, const T* u) const;
template <typename Derived>
class ModelImpl : public KinematicModel {
 public:
  Twist<double> BodyTwist(const double* p, const double* u) const final {
    return static_cast<const Derived*>(this)->Eval(p, u);
  }
  Twist<Jet> BodyTwist(const Jet* p, const Jet* u) const final {
    return static_cast<const Derived*>(this)->Eval(p, u);
  }
  Twist<BJet> BodyTwist(const BJet* p, const BJet* u) const final {
    return static_cast<const Derived*>(this)->Eval(p, u);
  }
};

using ModelRegistry = Registry<KinematicModel>;
// The models in the one explicit list, src/core/models/model_list.cc.
void RegisterBuiltins(Registry<KinematicModel>* registry);

// Creates a registered model; an unknown name is an error naming the known models.
Status MakeModel(std::string_view name, std::shared_ptr<const KinematicModel>* out);
// The same as a value.
StatusOr<std::shared_ptr<const KinematicModel>> MakeModel(std::string_view name);

// The parameters' names as a list for messages ("k_v, k_steer, steer_offset, wheelbase").
std::string ParamNames(const std::vector<ParamInfo>& params);

// Empty when `v` is a value the parameter `p` can take: finite, and at least its physical
// bound (ParamInfo::min_value, which the batch fits hold); otherwise what is wrong, naming
// the parameter ("'d' must be >= 1e-06 m (its physical bound), not 0"). For values from
// outside: a guess, a held value, a simulated truth.
std::string ParamValueProblem(const ParamInfo& p, double v);

}  // namespace kincal

// Ends a model's implementation file, after its anonymous namespace, inside namespace
// kincal: the factory src/core/models/model_list.cc registers.
#define KINCAL_MODEL_FACTORY(Class) \
  std::unique_ptr<KinematicModel> New##Class##Model() { return std::make_unique<Class>(); }
