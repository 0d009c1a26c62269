// Recursive estimators behind one interface: square-root DD2, EKF, UKF.
//
// A filter holds a Gaussian belief (mean, covariance) over a state vector and knows
// nothing about robots: the process and measurement are function objects, so the same
// filter runs a linear test system, a polar-to-Cartesian transform or an augmented
// kinematic state. Noise enters as square-root covariances (lower-triangular factors):
//   process:      x+ = f(x, v),  v ~ N(0, Sv Sv^T)
//   measurement:  z  = h(x) + w, w ~ N(0, Sw Sw^T)
// Angle components (state or measurement) are differenced with wrapping to (-pi, pi].
//
// No heap allocation per step: all vectors and matrices have compile-time maxima.
// Adding a filter: one file in src/estimation/ ending with KINCAL_FILTER_FACTORY(Class),
// and its lines in src/estimation/filter_list.cc.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/registry.h"
#include "kincal/status.h"
#include "kincal/types.h"

namespace kincal {

class ProcessFunction {
 public:
  virtual ~ProcessFunction() = default;
  virtual int state_dim() const = 0;
  virtual int noise_dim() const = 0;
  // out = f(x, v); v has noise_dim() entries.
  virtual void Eval(const double* x, const double* v, double* out) const = 0;
  // F = df/dx at (x, 0), G = df/dv at (x, 0). Default: central differences.
  virtual void Jacobians(const StateVec& x, StateMat* F, StateNoiseMat* G) const;
  virtual bool IsAngle(int /*i*/) const { return false; }
};

class MeasurementFunction {
 public:
  virtual ~MeasurementFunction() = default;
  virtual int state_dim() const = 0;
  virtual int meas_dim() const = 0;
  virtual void Eval(const double* x, double* z) const = 0;
  // H = dh/dx at x. Default: central differences.
  virtual void Jacobian(const StateVec& x, MeasStateMat* H) const;
  virtual bool IsAngle(int /*i*/) const { return false; }
};

struct UpdateResult {
  MeasVec innovation;      // z - predicted z (angles wrapped)
  MeasMat innovation_cov;  // predicted measurement covariance incl. noise
  double nis = 0.0;        // innovation^T cov^-1 innovation
  bool ok = true;          // false if the innovation covariance was not positive definite
  bool gated = false;      // the measurement failed the innovation gate and was not used
};

class Filter {
 public:
  virtual ~Filter() = default;
  virtual std::string_view name() const = 0;

  // angle_mask bit i set: state element i is an angle (wrapped after each update).
  virtual void Initialize(const StateVec& x, const StateMat& P, uint32_t angle_mask = 0) = 0;
  virtual void Predict(const ProcessFunction& f, const NoiseMat& Sv) = 0;
  virtual UpdateResult Update(const MeasurementFunction& h, const MeasVec& z,
                              const MeasMat& Sw) = 0;

  virtual const StateVec& mean() const = 0;
  virtual StateMat covariance() const = 0;
};

using FilterRegistry = Registry<Filter>;
// The filters in the one explicit list, src/estimation/filter_list.cc.
void RegisterBuiltins(Registry<Filter>* registry);

// Creates a registered filter; an unknown name is an error naming the known filters.
StatusOr<std::unique_ptr<Filter>> MakeFilter(std::string_view name);

// Lower-triangular L (n x n) with L L^T = A A^T, by Householder reflections on A^T
// (A is n x m, m >= n). Diagonal made non-negative.
using CompoundMat = MatN<kMaxState, 2 * (kMaxState + kMaxNoise)>;
void Triangularize(const CompoundMat& A, StateMat* L);

}  // namespace kincal

// Ends a filter's implementation file, after its anonymous namespace, inside namespace
// kincal: the factory src/estimation/filter_list.cc registers under its name.
#define KINCAL_FILTER_FACTORY(Class) \
  std::unique_ptr<Filter> New##Class##Filter() { return std::make_unique<Class>(); }
