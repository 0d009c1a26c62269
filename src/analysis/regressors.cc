#include "analysis/regressors.h"

#include <algorithm>
#include <cmath>

#include "kincal/angles.h"

namespace kincal::analysis {
namespace {

// The commanded twist is sampled at this many points across a window.
constexpr int kTwistSamples = 8;
// "Moving": a command above this fraction of the recording's largest; "small": below this
// fraction (where dead bands act).
constexpr double kMovingFraction = 1e-3;
constexpr double kSmallFraction = 0.25;
// A steering reversal compares the steering command with its value this long before.
constexpr double kSteerLookbackS = 0.5;
// The command lag: measured speed and turn rate from pose differences over 2 kLagHalfS,
// every kLagStepS; lags searched over +-kMaxLagS in steps of kLagSearchStepS; at least
// kMinLagSamples samples.
constexpr double kLagStepS = 0.05;
constexpr double kLagHalfS = 0.1;
constexpr double kMaxLagS = 5.0;
constexpr double kLagSearchStepS = 0.02;
constexpr size_t kMinLagSamples = 50;

}  // namespace

// Regressors per evaluation window, from the commanded body twist of the bare model.
void ComputeFeatures(Dataset* d, const System& bare, const Eigen::VectorXd& p) {
  const auto& u = d->rec->controls;
  const KinematicModel& m = bare.model();
  double vmax = 1e-12, wmax = 1e-12;
  auto twist = [&](double t) {
    const auto& c = u.At(t);
    return m.BodyTwist(p.data(), c.data());
  };
  for (size_t i = 0; i < u.size(); ++i) {
    const auto tw = m.BodyTwist(p.data(), u.ValuesAt(static_cast<int>(i)).data());
    vmax = std::max(vmax, std::abs(tw.vx));
    wmax = std::max(wmax, std::abs(tw.omega));
  }
  const int sc = m.steering_channel();
  d->features.clear();
  for (const auto& w : d->eval) {
    const double ta = d->t[static_cast<size_t>(w.start)], tb = d->t[static_cast<size_t>(w.end)];
    RegressorValues f;
    double sv = 0, sw = 0, sav = 0, saw = 0, sww = 0, svw = 0, mov = 0, smv = 0, smw = 0;
    const int K = kTwistSamples;
    for (int k = 0; k < K; ++k) {
      const auto tw = twist(ta + (k + 0.5) * (tb - ta) / K);
      sv += tw.vx;
      sw += tw.omega;
      sav += std::abs(tw.vx);
      saw += std::abs(tw.omega);
      sww += tw.omega * std::abs(tw.omega);
      svw += tw.vx * tw.omega;
      mov +=
          (std::abs(tw.vx) > kMovingFraction * vmax || std::abs(tw.omega) > kMovingFraction * wmax)
              ? 1.0
              : 0.0;
      smv += (std::abs(tw.vx) > 0 && std::abs(tw.vx) < kSmallFraction * vmax)
                 ? (tw.vx > 0 ? 1.0 : -1.0)
                 : 0.0;
      smw += (std::abs(tw.omega) > 0 && std::abs(tw.omega) < kSmallFraction * wmax)
                 ? (tw.omega > 0 ? 1.0 : -1.0)
                 : 0.0;
    }
    const auto a = twist(ta), b = twist(tb);
    f.Set(Regressor::kSpeed, sv / K);
    f.Set(Regressor::kTurnRate, sw / K);
    f.Set(Regressor::kAbsSpeed, sav / K);
    f.Set(Regressor::kAbsTurnRate, saw / K);
    f.Set(Regressor::kTurnRateSq, sww / K);
    f.Set(Regressor::kLatAccel, svw / K);
    f.Set(Regressor::kMoving, mov / K);
    f.Set(Regressor::kSmallSpeed, smv / K);
    f.Set(Regressor::kSmallTurn, smw / K);
    f.Set(Regressor::kAccel, b.vx - a.vx);
    f.Set(Regressor::kYawAccel, b.omega - a.omega);
    f.Set(Regressor::kConst, 1.0);
    const double th = d->rec->poses[static_cast<size_t>(w.start)].z.z();
    f.Set(Regressor::kCosHeading, std::cos(th));
    f.Set(Regressor::kSinHeading, std::sin(th));
    f.Set(Regressor::kTime, ta);
    if (sc >= 0) {
      const double s_now = u.At(ta)[static_cast<size_t>(sc)];
      const double s_before = u.At(ta - kSteerLookbackS)[static_cast<size_t>(sc)];
      f.Set(Regressor::kSteerReversal, s_now > s_before ? 1.0 : (s_now < s_before ? -1.0 : 0.0));
    }
    d->features.push_back(std::move(f));
  }
}

namespace {

// The measured forward speed and turn rate over windows of +-kLagHalfS around a grid every
// kLagStepS of the fitted (not held-out) span, and the grid's times.
struct MeasuredMotion {
  std::vector<double> v, w, t;
};

MeasuredMotion SampleMeasuredMotion(const Dataset& d) {
  const auto& P = d.rec->poses;
  const double dt = kLagStepS, half = kLagHalfS;
  MeasuredMotion m;
  // The window's ends walk forward with the grid (the first pose at or after each end, as
  // a binary search finds it, in one pass: a thinned store spans hours of grid).
  const size_t num_poses = d.t.size();
  size_t i = 0, j = 0;
  for (double t = std::max(d.t.front(), d.t_ctrl0) + half; t < d.t_split - half; t += dt) {
    while (i < num_poses && d.t[i] < t - half) ++i;
    while (j < num_poses && d.t[j] < t + half) ++j;
    if (i == num_poses || j == num_poses || j <= i) continue;
    if (d.HeldOutAt(t)) continue;
    if (d.by_runs && d.run[i] != d.run[j]) continue;  // never across a run's start
    const double span = d.t[j] - d.t[i];
    if (span < half || span > 4 * half) continue;
    const Eigen::Vector2d dp = P[j].z.head<2>() - P[i].z.head<2>();
    const double th = P[i].z.z() + 0.5 * WrapAngle(P[j].z.z() - P[i].z.z());
    m.v.push_back((std::cos(th) * dp.x() + std::sin(th) * dp.y()) / span);
    m.w.push_back(WrapAngle(P[j].z.z() - P[i].z.z()) / span);
    m.t.push_back(t);
  }
  return m;
}

}  // namespace

// Lag (s) by which the measured motion follows the commanded one, from the
// cross-correlation of measured and commanded forward speed and turn rate over lags in
// [-5, 5] s. The start for timing effects: a clock offset of seconds is far outside the
// basin of a local fit started at zero.
double EstimateCommandLag(const Dataset& d, const System& bare, const Eigen::VectorXd& p) {
  const auto& u = d.rec->controls;
  const MeasuredMotion measured = SampleMeasuredMotion(d);
  const std::vector<double>&vm = measured.v, &wm = measured.w, &tgrid = measured.t;
  if (vm.size() < kMinLagSamples) return 0.0;
  auto corr = [](const std::vector<double>& a, const std::vector<double>& b) {
    const double n = static_cast<double>(a.size());
    const double ma = std::accumulate(a.begin(), a.end(), 0.0) / n;
    const double mb = std::accumulate(b.begin(), b.end(), 0.0) / n;
    double sab = 0, saa = 0, sbb = 0;
    for (size_t k = 0; k < a.size(); ++k) {
      sab += (a[k] - ma) * (b[k] - mb);
      saa += (a[k] - ma) * (a[k] - ma);
      sbb += (b[k] - mb) * (b[k] - mb);
    }
    return (saa > 0 && sbb > 0) ? sab / std::sqrt(saa * sbb) : 0.0;
  };
  // The commanded twist is constant between control samples: evaluate it once per sample
  // (index -1: before the first, zero controls), then walk the sorted grid for each lag.
  const int m = static_cast<int>(u.size());
  std::vector<Twist<double>> commanded(static_cast<size_t>(m) + 1);
  for (int i = -1; i < m; ++i) {
    commanded[static_cast<size_t>(i + 1)] = bare.model().BodyTwist(p.data(), u.ValuesAt(i).data());
  }
  double best = -1e300, best_lag = 0.0;
  std::vector<double> vc(vm.size()), wc(vm.size());
  for (double lag = -kMaxLagS; lag <= kMaxLagS + 1e-9; lag += kLagSearchStepS) {
    int idx = u.IndexAt(tgrid.front() - lag);
    for (size_t k = 0; k < tgrid.size(); ++k) {
      while (idx + 1 < m && u.TimeAt(idx + 1) <= tgrid[k] - lag) ++idx;
      const Twist<double>& tw = commanded[static_cast<size_t>(idx + 1)];
      vc[k] = tw.vx;
      wc[k] = tw.omega;
    }
    const double c = corr(vm, vc) + corr(wm, wc);
    if (c > best) {
      best = c;
      best_lag = lag;
    }
  }
  return best_lag;
}

}  // namespace kincal::analysis
