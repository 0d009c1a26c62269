// Helpers for the tests of single models and effects: a model's body twist, and the pose a
// System reaches from the origin under one constant command, beside the closed form.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "kincal/model.h"
#include "kincal/system.h"

namespace kincal::testing {

// Body twist of a registered model at parameters p and controls u.
inline Twist<double> TwistOf(const char* model, std::vector<double> p, std::vector<double> u) {
  return MakeModel(model).value()->BodyTwist(p.data(), u.data());
}

// Pose (x, y, theta) after t_s seconds of `command`, held from t = 0, starting at the
// origin heading along +x with the effect states at rest (all commands zero before t = 0).
inline Eigen::Vector3d PoseAfter(const System& sys, const std::vector<double>& params,
                                 const std::vector<double>& command, double t_s) {
  ControlSignal u(sys.num_controls(), 0);
  u.Append(0, command);
  VecN<kMaxState> p(sys.num_params());
  for (int i = 0; i < sys.num_params(); ++i) p[i] = params[static_cast<size_t>(i)];
  const StateVec x = sys.MakeState(0, 0, 0, p, u, -1.0);
  StateVec out(x.size());
  sys.Propagate(x.data(), out.data(), 0.0, t_s, u, static_cast<const double*>(nullptr));
  return out.head<3>();
}

// Closed form: the pose after t_s seconds of a constant body twist (vx, vy, omega) from
// the origin heading along +x.
inline Eigen::Vector3d ArcPose(double vx, double vy, double omega, double t_s) {
  const double th = omega * t_s;
  if (std::abs(omega) < 1e-12) return {vx * t_s, vy * t_s, 0.0};
  const double s = std::sin(th), c = 1.0 - std::cos(th);
  return {(vx * s - vy * c) / omega, (vx * c + vy * s) / omega, th};
}

}  // namespace kincal::testing
