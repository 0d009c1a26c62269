#include "analysis/evaluation.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "kincal/angles.h"

namespace kincal::analysis {

Evaluation Evaluate(const System& sys, const Eigen::VectorXd& p, const Dataset& d) {
  const auto& u = d.rec->controls;
  const int n = sys.state_dim();
  // Effect states along the recording (they depend on commands and parameters only),
  // at rest again at each run's start.
  std::vector<StateVec> states;
  if (sys.num_states() > 0) {
    StateVec x = sys.MakeState(0, 0, 0, p, u, d.t_ctrl0);
    double t = d.t_ctrl0;
    int run = 0;
    for (const auto& w : d.eval) {
      const double ts = d.t[static_cast<size_t>(w.start)];
      if (d.by_runs && d.run[static_cast<size_t>(w.start)] != run) {
        run = d.run[static_cast<size_t>(w.start)];
        t = std::max(d.t_ctrl0, d.run_start_s[static_cast<size_t>(run)]);
        x = sys.MakeState(0, 0, 0, p, u, t);
      }
      if (ts > t) {
        sys.AdvanceEffectStates(x.data(), t, ts, u);
        t = ts;
      }
      states.push_back(x);
    }
  }
  Evaluation e;
  double sp[2] = {0, 0}, sh[2] = {0, 0};
  int cnt[2] = {0, 0};
  for (size_t k = 0; k < d.eval.size(); ++k) {
    const auto& w = d.eval[k];
    const auto& zs = d.rec->poses[static_cast<size_t>(w.start)].z;
    const auto& ze = d.rec->poses[static_cast<size_t>(w.end)].z;
    StateVec x(n);
    x.setZero();
    x.segment(3, sys.num_params()) = p;
    if (!states.empty()) x.tail(sys.num_states()) = states[k].tail(sys.num_states());
    sys.SetPoseFromMeasurement(zs.data(), x.data());
    sys.Propagate(x.data(), x.data(), d.t[static_cast<size_t>(w.start)],
                  d.t[static_cast<size_t>(w.end)], u, static_cast<const double*>(nullptr));
    double zp[3];
    sys.Measure(x.data(), zp);
    const double ex = ze.x() - zp[0], ey = ze.y() - zp[1];
    const double c = std::cos(ze.z()), s = std::sin(ze.z());
    ResidualPoint r{d.t[static_cast<size_t>(w.start)],
                    d.HeldOutAt(d.t[static_cast<size_t>(w.start)]), c * ex + s * ey,
                    -s * ex + c * ey, WrapAngle(ze.z() - zp[2])};
    const int h = r.heldout ? 1 : 0;
    sp[h] += r.along * r.along + r.cross * r.cross;
    sh[h] += r.heading * r.heading;
    ++cnt[h];
    e.points.push_back(r);
  }
  e.fit = {std::sqrt(sp[0] / std::max(1, cnt[0])), std::sqrt(sh[0] / std::max(1, cnt[0])), cnt[0]};
  e.held = {std::sqrt(sp[1] / std::max(1, cnt[1])), std::sqrt(sh[1] / std::max(1, cnt[1])), cnt[1]};
  return e;
}

void NaiveHeldOut(const Dataset& d, double* standstill_m, double* constant_velocity_m) {
  double still = 0.0, moving = 0.0;
  int n = 0;
  for (const auto& w : d.eval) {
    const double ts = d.t[static_cast<size_t>(w.start)], te = d.t[static_cast<size_t>(w.end)];
    if (!d.HeldOutAt(ts)) continue;
    // The pose about one horizon earlier: the velocity over the previous horizon.
    const auto prev = std::lower_bound(d.t.begin(), d.t.begin() + w.start, ts - d.horizon);
    const int k = static_cast<int>(prev - d.t.begin());
    if (k >= w.start ||
        (d.by_runs && d.run[static_cast<size_t>(k)] != d.run[static_cast<size_t>(w.start)]))
      continue;
    const Eigen::Vector2d zs = d.rec->poses[static_cast<size_t>(w.start)].z.head<2>();
    const Eigen::Vector2d ze = d.rec->poses[static_cast<size_t>(w.end)].z.head<2>();
    const Eigen::Vector2d zk = d.rec->poses[static_cast<size_t>(k)].z.head<2>();
    const Eigen::Vector2d v = (zs - zk) / (ts - d.t[static_cast<size_t>(k)]);
    still += (ze - zs).squaredNorm();
    moving += (ze - zs - v * (te - ts)).squaredNorm();
    ++n;
  }
  *standstill_m = n > 0 ? std::sqrt(still / n) : 0.0;
  *constant_velocity_m = n > 0 ? std::sqrt(moving / n) : 0.0;
}

double Combined(const ErrorStats& s, const Eigen::Vector2d& sigma) {
  return std::sqrt(s.pos_rms_m * s.pos_rms_m / (2.0 * sigma[0] * sigma[0]) +
                   s.heading_rms_rad * s.heading_rms_rad / (sigma[1] * sigma[1]));
}

ResidualTests TestResiduals(const Evaluation& e, double horizon) {
  ResidualTests t;
  // Non-overlapping fit windows: take points at least one horizon apart.
  std::vector<const ResidualPoint*> pts;
  double last = -1e300;
  for (const auto& p : e.points) {
    if (p.heldout) continue;
    if (p.t_s >= last + horizon) {
      pts.push_back(&p);
      last = p.t_s;
    }
  }
  const int n = static_cast<int>(pts.size());
  if (n < 12) return t;
  for (int c = 0; c < 3; ++c) {
    std::vector<double> y;
    for (const auto* p : pts) y.push_back(c == 0 ? p->along : (c == 1 ? p->cross : p->heading));
    const double m = std::accumulate(y.begin(), y.end(), 0.0) / n;
    double v = 0;
    for (double a : y) v += (a - m) * (a - m);
    v /= n;
    t.bias_z[c] = v > 0 ? m / std::sqrt(v / n) : 0.0;
    double q = 0;
    const int lags = std::min(10, n / 4);
    for (int k = 1; k <= lags; ++k) {
      double ac = 0;
      for (int i = k; i < n; ++i)
        ac += (y[static_cast<size_t>(i)] - m) * (y[static_cast<size_t>(i - k)] - m);
      ac = v > 0 ? ac / (n * v) : 0.0;
      if (k == 1) t.lag1_autocorr[c] = ac;
      q += ac * ac / (n - k);
    }
    q *= n * (n + 2.0);
    // Chi-square(lags) upper tail by the Wilson-Hilferty approximation.
    const double k = lags;
    const double zq = (std::cbrt(q / k) - (1.0 - 2.0 / (9.0 * k))) / std::sqrt(2.0 / (9.0 * k));
    t.ljung_box_p[c] = 0.5 * std::erfc(zq / std::sqrt(2.0));
  }
  return t;
}

}  // namespace kincal::analysis
