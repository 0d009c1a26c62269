#include "plan/shaping.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace kincal::plan_internal {

namespace {

// How long the slowest of `num_channels` channels needs from `from` to `to` at its
// acceleration limit (0 without limits).
double RampSeconds(const Values& from, const Values& to, int num_channels, const PlanOptions& o) {
  double ramp_s = 0.0;
  for (size_t i = 0; i < static_cast<size_t>(num_channels); ++i) {
    const double a = i < o.max_accel.size() ? o.max_accel[i] : 0.0;
    if (a > 0.0) ramp_s = std::max(ramp_s, std::abs(to[i] - from[i]) / a);
  }
  return ramp_s;
}

}  // namespace

void AppendSlewed(ControlSignal* signal, double t0_s, double t1_s, const Values& to,
                  const PlanOptions& o, Values* u) {
  const double dt = 1.0 / o.control_rate_hz;
  const int nc = signal->num_channels();
  // All channels arrive together: a straight ramp in control space (for a model linear
  // in its controls, a straight ramp of the twist), as long as the slowest channel needs.
  const double ramp_s = RampSeconds(*u, to, nc, o);
  Values rate{};
  for (int c = 0; c < nc; ++c) {
    const size_t i = static_cast<size_t>(c);
    rate[i] = ramp_s > 0.0 ? std::abs(to[i] - (*u)[i]) / ramp_s : 0.0;
  }
  for (double t = t0_s; t < t1_s - 1e-9; t += dt) {
    for (int c = 0; c < nc; ++c) {
      const size_t i = static_cast<size_t>(c);
      double& x = (*u)[i];
      x = ramp_s > 0.0 ? x + std::clamp(to[i] - x, -rate[i] * dt, rate[i] * dt) : to[i];
    }
    signal->Append(signal->ToNs(t), std::span<const double>(u->data(), static_cast<size_t>(nc)));
  }
}

void AppendRest(ControlSignal* signal, double t_s) {
  const Values zero{};
  signal->Append(signal->ToNs(t_s),
                 std::span<const double>(zero.data(), static_cast<size_t>(signal->num_channels())));
}

void AppendSamplesBefore(ControlSignal* signal, const ControlSignal& from, double t_s) {
  const size_t nc = static_cast<size_t>(from.num_channels());
  for (int i = 0; i < static_cast<int>(from.size()) && from.TimeAt(i) < t_s - 1e-9; ++i) {
    signal->Append(signal->ToNs(from.TimeAt(i)),
                   std::span<const double>(from.ValuesAt(i).data(), nc));
  }
}

double AppendStop(ControlSignal* signal, double t0_s, const PlanOptions& o, Values* u) {
  const double ramp_s = RampSeconds(*u, Values{}, signal->num_channels(), o);
  const double dt = 1.0 / o.control_rate_hz;
  const double rest_s = t0_s + dt * std::ceil(ramp_s / dt - 1e-9);
  AppendSlewed(signal, t0_s, rest_s, Values{}, o, u);
  *u = Values{};
  AppendRest(signal, rest_s);
  return rest_s;
}

void AppendStopAndRest(ControlSignal* signal, double t0_s, double end_s, const PlanOptions& o,
                       Values* u) {
  if (AppendStop(signal, t0_s, o, u) < end_s - 1e-9) AppendRest(signal, end_s);
}

double LongestStopSeconds(const PlanOptions& o, int num_channels) {
  Values limit{};
  for (size_t i = 0; i < static_cast<size_t>(num_channels) && i < o.max_abs.size(); ++i) {
    limit[i] = o.max_abs[i];
  }
  const double dt = 1.0 / o.control_rate_hz;
  return dt * std::ceil(RampSeconds(limit, Values{}, num_channels, o) / dt - 1e-9);
}

Eigen::Vector2d TwistOf(const System& sys, const Eigen::VectorXd& params, const Values& u) {
  const Twist<double> tw = sys.model().BodyTwist(params.data(), u.data());
  return {tw.vx, tw.omega};
}

bool TwistToControls(const System& sys, const Eigen::VectorXd& params, double v, double omega,
                     const PlanOptions& o, Values* u) {
  const int nc = sys.num_controls();
  const Eigen::Vector2d want(v, omega);
  Values x{};
  for (int c = 0; c < nc; ++c) x[static_cast<size_t>(c)] = 0.1 * o.max_abs[static_cast<size_t>(c)];
  double lambda = 1e-3;
  Eigen::Vector2d r = TwistOf(sys, params, x) - want;
  for (int it = 0; it < 100 && r.norm() > 1e-9; ++it) {
    Eigen::MatrixXd J(2, nc);
    for (int c = 0; c < nc; ++c) {
      Values xp = x;
      const double h = 1e-6 * o.max_abs[static_cast<size_t>(c)];
      xp[static_cast<size_t>(c)] += h;
      J.col(c) = (TwistOf(sys, params, xp) - TwistOf(sys, params, x)) / h;
    }
    Eigen::MatrixXd A = J.transpose() * J;
    A.diagonal().array() += lambda * (A.diagonal().array() + 1e-12);
    const Eigen::VectorXd step = A.ldlt().solve(-J.transpose() * r);
    Values xn = x;
    for (int c = 0; c < nc; ++c) {
      const size_t i = static_cast<size_t>(c);
      xn[i] = std::clamp(x[i] + step[c], -o.max_abs[i], o.max_abs[i]);
    }
    const Eigen::Vector2d rn = TwistOf(sys, params, xn) - want;
    if (rn.norm() < r.norm()) {
      x = xn;
      r = rn;
      lambda = std::max(lambda / 10.0, 1e-9);
    } else {
      lambda *= 10.0;
    }
  }
  *u = x;
  return r.norm() <= 1e-6 * want.norm() + 1e-12;
}

}  // namespace kincal::plan_internal
