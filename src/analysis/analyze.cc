#include "kincal/analysis/analyze.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>

#include "kincal/angles.h"
#include "kincal/estimation/batch.h"
#include "kincal/system.h"

namespace kincal {

bool AnalyzeOptions::IsValid(std::string* error) const {
  if (!(fit_fraction > 0.05 && fit_fraction < 0.95)) {
    *error = "--fit-fraction must be in (0.05, 0.95)";
    return false;
  }
  if (!(horizon_s > 0.0)) {
    *error = "--horizon must be > 0 s";
    return false;
  }
  if (effects_mode != "auto" && effects_mode != "none" && effects_mode != "list") {
    *error = "--effects must be auto, none or a list of effect names";
    return false;
  }
  if (pose_sigma && !((pose_sigma->array() > 0.0).all())) {
    *error = "pose sigmas must be > 0";
    return false;
  }
  if (max_fit_windows < 10 || max_eval_windows < 10 || poses_per_window < 1 || max_effects < 0) {
    *error = "max_fit_windows, max_eval_windows >= 10, poses_per_window >= 1 expected";
    return false;
  }
  return true;
}

namespace {

constexpr const char* kComponents[3] = {"along", "cross", "heading"};

struct Window {
  int start;  // pose index
  int end;    // pose index of the horizon end
};

// Regressors describing what the robot was commanded to do during a window.
struct Features {
  std::map<std::string, double> v;
};

struct Dataset {
  const Recording* rec = nullptr;
  std::vector<double> t;  // pose times, s since origin
  double t_ctrl0 = 0, t_ctrl1 = 0, t_split = 0;
  double horizon = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector2d sigma{1, 1};
  std::vector<Window> eval;           // every (strided) pose with a horizon end
  std::vector<Window> fit_windows;    // non-overlapping, in the fit span
  std::vector<Window> short_windows;  // shorter, for the multi-start stage
  std::vector<PoseMeasurement> fit_meas, short_meas;
  std::vector<Features> features;  // per eval window
};

int FindEnd(const std::vector<double>& t, int i, double h) {
  const double target = t[static_cast<size_t>(i)] + h;
  const auto it = std::lower_bound(t.begin() + i, t.end(), target - 1e-9);
  if (it == t.end()) return -1;
  const int j = static_cast<int>(it - t.begin());
  if (t[static_cast<size_t>(j)] - target > 0.1 * h + 1e-3) return -1;  // a gap
  return j;
}

std::vector<Window> NonOverlapping(const Dataset& d, double h, double t0, double t1, int max_n) {
  std::vector<Window> w;
  const auto& t = d.t;
  int i = static_cast<int>(std::lower_bound(t.begin(), t.end(), t0) - t.begin());
  while (i < static_cast<int>(t.size()) && t[static_cast<size_t>(i)] + h <= t1) {
    const int j = FindEnd(t, i, h);
    if (j < 0) {
      ++i;
      continue;
    }
    w.push_back({i, j});
    i = j;
  }
  if (static_cast<int>(w.size()) > max_n) {
    std::vector<Window> sub;
    for (int k = 0; k < max_n; ++k)
      sub.push_back(w[static_cast<size_t>(k) * w.size() / static_cast<size_t>(max_n)]);
    w = sub;
  }
  return w;
}

std::vector<PoseMeasurement> WindowMeasurements(const Dataset& d, const std::vector<Window>& ws,
                                                int per_window) {
  std::vector<PoseMeasurement> m;
  for (size_t k = 0; k < ws.size(); ++k) {
    const auto& w = ws[k];
    std::vector<int> idx = {w.start};
    const int span = w.end - w.start;
    const int n = std::min(per_window, span);
    for (int q = 1; q <= n; ++q)
      idx.push_back(w.start + static_cast<int>(std::lround(static_cast<double>(q) * span / n)));
    idx.erase(std::unique(idx.begin(), idx.end()), idx.end());
    for (int i : idx) {
      const auto& p = d.rec->poses[static_cast<size_t>(i)];
      m.push_back({p.t_ns, p.z, d.R, static_cast<int>(k)});
    }
  }
  return m;
}

Eigen::Vector2d EstimatePoseSigma(const Recording& rec) {
  std::vector<double> dp, dh;
  const auto& P = rec.poses;
  for (size_t i = 1; i + 1 < P.size(); ++i) {
    const double a = NsToSeconds(P[i].t_ns - P[i - 1].t_ns),
                 b = NsToSeconds(P[i + 1].t_ns - P[i].t_ns);
    if (a <= 0 || b <= 0 || std::abs(a - b) > 0.2 * std::max(a, b) || a > 0.2) continue;
    const Eigen::Vector2d d2 = P[i + 1].z.head<2>() - 2 * P[i].z.head<2>() + P[i - 1].z.head<2>();
    dp.push_back(d2.x());
    dp.push_back(d2.y());
    dh.push_back(WrapAngle(P[i + 1].z.z() - P[i].z.z()) - WrapAngle(P[i].z.z() - P[i - 1].z.z()));
  }
  auto robust_sigma = [](std::vector<double> v, double floor) {
    if (v.size() < 10) return floor;
    const auto mid = v.begin() + static_cast<long>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    const double med = *mid;
    for (auto& x : v) x = std::abs(x - med);
    std::nth_element(v.begin(), mid, v.end());
    // Second difference of white noise has variance 6 sigma^2.
    return std::max(floor, 1.4826 * *mid / std::sqrt(6.0));
  };
  return {robust_sigma(dp, 1e-4), robust_sigma(dh, 1e-4)};
}

Dataset Prepare(const Recording& rec, const AnalyzeOptions& o, std::vector<std::string>* warnings) {
  Dataset d;
  d.rec = &rec;
  d.horizon = o.horizon_s;
  if (rec.poses.size() < 20)
    throw AnalysisError(rec.source + ": only " + std::to_string(rec.poses.size()) +
                        " poses; at least 20 are needed");
  if (rec.controls.size() < 2) throw AnalysisError(rec.source + ": fewer than 2 control samples");
  for (const auto& p : rec.poses) d.t.push_back(rec.controls.ToSeconds(p.t_ns));
  d.t_ctrl0 = rec.controls.TimeAt(0);
  d.t_ctrl1 = rec.controls.TimeAt(static_cast<int>(rec.controls.size()) - 1);
  const double t0 = std::max(d.t.front(), d.t_ctrl0);
  const double t1 = std::min(d.t.back(), d.t_ctrl1 + o.horizon_s);
  if (t1 - t0 < 4.0 * o.horizon_s) {
    std::ostringstream m;
    m << rec.source << ": controls and poses overlap for only " << std::max(0.0, t1 - t0)
      << " s; at least 4 horizons (" << 4.0 * o.horizon_s << " s) are needed";
    throw AnalysisError(m.str());
  }
  if (d.t_ctrl0 > d.t.front() + 1.0) {
    std::ostringstream m;
    m << "poses start " << d.t_ctrl0 - d.t.front()
      << " s before the first control; that part is not used";
    warnings->push_back(m.str());
  }
  d.t_split = t0 + o.fit_fraction * (t1 - t0);
  d.sigma = o.pose_sigma ? *o.pose_sigma : EstimatePoseSigma(rec);
  d.R = Eigen::Vector3d(d.sigma[0] * d.sigma[0], d.sigma[0] * d.sigma[0], d.sigma[1] * d.sigma[1])
            .asDiagonal();
  // Evaluation windows from (strided) measured poses; none straddles the split.
  const int first = static_cast<int>(std::lower_bound(d.t.begin(), d.t.end(), t0) - d.t.begin());
  const int n = static_cast<int>(d.t.size());
  const int stride = std::max(1, (n - first) / o.max_eval_windows);
  for (int i = first; i < n; i += stride) {
    const int j = FindEnd(d.t, i, o.horizon_s);
    if (j < 0 || d.t[static_cast<size_t>(j)] > t1) continue;
    const bool fit = d.t[static_cast<size_t>(j)] <= d.t_split;
    const bool held = d.t[static_cast<size_t>(i)] >= d.t_split;
    if (fit || held) d.eval.push_back({i, j});
  }
  d.fit_windows = NonOverlapping(d, o.horizon_s, t0, d.t_split, o.max_fit_windows);
  const double hs = std::max(0.2, 0.25 * o.horizon_s);
  d.short_windows = NonOverlapping(d, hs, t0, d.t_split, std::min(150, o.max_fit_windows));
  if (d.fit_windows.size() < 5)
    throw AnalysisError(rec.source +
                        ": fewer than 5 prediction windows in the fit part (gaps, or a recording "
                        "shorter than a few horizons)");
  int held = 0;
  for (const auto& w : d.eval) held += d.t[static_cast<size_t>(w.start)] >= d.t_split;
  if (held < 5)
    throw AnalysisError(rec.source +
                        ": fewer than 5 prediction windows in the held-out part; lower "
                        "--fit-fraction or --horizon");
  d.fit_meas = WindowMeasurements(d, d.fit_windows, o.poses_per_window);
  d.short_meas = WindowMeasurements(d, d.short_windows, std::max(2, o.poses_per_window / 2));
  return d;
}

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
    Features f;
    double sv = 0, sw = 0, sav = 0, saw = 0, sww = 0, svw = 0, mov = 0, smv = 0, smw = 0;
    const int K = 8;
    for (int k = 0; k < K; ++k) {
      const auto tw = twist(ta + (k + 0.5) * (tb - ta) / K);
      sv += tw.vx;
      sw += tw.omega;
      sav += std::abs(tw.vx);
      saw += std::abs(tw.omega);
      sww += tw.omega * std::abs(tw.omega);
      svw += tw.vx * tw.omega;
      mov += (std::abs(tw.vx) > 1e-3 * vmax || std::abs(tw.omega) > 1e-3 * wmax) ? 1.0 : 0.0;
      smv +=
          (std::abs(tw.vx) > 0 && std::abs(tw.vx) < 0.25 * vmax) ? (tw.vx > 0 ? 1.0 : -1.0) : 0.0;
      smw += (std::abs(tw.omega) > 0 && std::abs(tw.omega) < 0.25 * wmax)
                 ? (tw.omega > 0 ? 1.0 : -1.0)
                 : 0.0;
    }
    const auto a = twist(ta), b = twist(tb);
    f.v["speed"] = sv / K;
    f.v["turn_rate"] = sw / K;
    f.v["abs_speed"] = sav / K;
    f.v["abs_turn_rate"] = saw / K;
    f.v["turn_rate_sq"] = sww / K;
    f.v["lat_accel"] = svw / K;
    f.v["moving"] = mov / K;
    f.v["small_speed"] = smv / K;
    f.v["small_turn"] = smw / K;
    f.v["accel"] = b.vx - a.vx;
    f.v["yaw_accel"] = b.omega - a.omega;
    f.v["const"] = 1.0;
    const double th = d->rec->poses[static_cast<size_t>(w.start)].z.z();
    f.v["cos_heading"] = std::cos(th);
    f.v["sin_heading"] = std::sin(th);
    f.v["time"] = ta;
    if (sc >= 0) {
      const double s_now = u.At(ta)[static_cast<size_t>(sc)];
      const double s_before = u.At(ta - 0.5)[static_cast<size_t>(sc)];
      f.v["steer_reversal"] = s_now > s_before ? 1.0 : (s_now < s_before ? -1.0 : 0.0);
    }
    d->features.push_back(std::move(f));
  }
}

// Lag (s) by which the measured motion follows the commanded one, from the
// cross-correlation of measured and commanded forward speed and turn rate over lags in
// [-5, 5] s. The start for timing effects: a clock offset of seconds is far outside the
// basin of a local fit started at zero.
double EstimateCommandLag(const Dataset& d, const System& bare, const Eigen::VectorXd& p) {
  const auto& P = d.rec->poses;
  const auto& u = d.rec->controls;
  const double dt = 0.05, half = 0.1;
  std::vector<double> vm, wm, tgrid;
  for (double t = std::max(d.t.front(), d.t_ctrl0) + half; t < d.t_split - half; t += dt) {
    const auto a = std::lower_bound(d.t.begin(), d.t.end(), t - half);
    const auto b = std::lower_bound(d.t.begin(), d.t.end(), t + half);
    if (a == d.t.end() || b == d.t.end() || b <= a) continue;
    const size_t i = static_cast<size_t>(a - d.t.begin()), j = static_cast<size_t>(b - d.t.begin());
    const double span = d.t[j] - d.t[i];
    if (span < half || span > 4 * half) continue;
    const Eigen::Vector2d dp = P[j].z.head<2>() - P[i].z.head<2>();
    const double th = P[i].z.z() + 0.5 * WrapAngle(P[j].z.z() - P[i].z.z());
    vm.push_back((std::cos(th) * dp.x() + std::sin(th) * dp.y()) / span);
    wm.push_back(WrapAngle(P[j].z.z() - P[i].z.z()) / span);
    tgrid.push_back(t);
  }
  if (vm.size() < 50) return 0.0;
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
  double best = -1e300, best_lag = 0.0;
  std::vector<double> vc(vm.size()), wc(vm.size());
  for (double lag = -5.0; lag <= 5.0 + 1e-9; lag += 0.02) {
    for (size_t k = 0; k < tgrid.size(); ++k) {
      const auto tw = bare.model().BodyTwist(p.data(), u.At(tgrid[k] - lag).data());
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

struct Evaluation {
  ErrorStats fit, held;
  std::vector<ResidualPoint> points;
};

Evaluation Evaluate(const System& sys, const Eigen::VectorXd& p, const Dataset& d) {
  const auto& u = d.rec->controls;
  const int n = sys.state_dim();
  // Effect states along the recording (they depend on commands and parameters only).
  std::vector<StateVec> states;
  if (sys.num_states() > 0) {
    StateVec x = sys.MakeState(0, 0, 0, p, u, d.t_ctrl0);
    double t = d.t_ctrl0;
    for (const auto& w : d.eval) {
      const double ts = d.t[static_cast<size_t>(w.start)];
      if (ts > t) {
        sys.Propagate(x.data(), x.data(), t, ts, u, static_cast<const double*>(nullptr));
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
                    d.t[static_cast<size_t>(w.start)] >= d.t_split, c * ex + s * ey,
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

double Combined(const ErrorStats& s, const Eigen::Vector2d& sigma) {
  return std::sqrt(s.pos_rms_m * s.pos_rms_m / (2.0 * sigma[0] * sigma[0]) +
                   s.heading_rms_rad * s.heading_rms_rad / (sigma[1] * sigma[1]));
}

std::vector<DiagnosisTerm> Diagnose(const Dataset& d, const Evaluation& e) {
  std::vector<DiagnosisTerm> out;
  if (d.features.empty()) return out;
  // Effective number of independent windows: windows start at every (strided) pose but
  // overlap over one horizon.
  std::vector<size_t> fit_idx;
  for (size_t k = 0; k < e.points.size(); ++k) {
    if (!e.points[k].heldout) fit_idx.push_back(k);
  }
  if (fit_idx.size() < 10) return out;
  const double span = e.points[fit_idx.back()].t_s - e.points[fit_idx.front()].t_s;
  const double n_eff =
      std::max(2.0, std::min<double>(static_cast<double>(fit_idx.size()), span / d.horizon));
  for (int c = 0; c < 3; ++c) {
    std::vector<double> y;
    for (size_t k : fit_idx) {
      const auto& p = e.points[k];
      y.push_back(c == 0 ? p.along : (c == 1 ? p.cross : p.heading));
    }
    const double my = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(y.size());
    double syy = 0;
    for (double v : y) syy += (v - my) * (v - my);
    for (const auto& [name, dummy] : d.features.front().v) {
      (void)dummy;
      DiagnosisTerm t{kComponents[c], name, 0.0, 0.0};
      if (name == "const") {
        // Bias: mean over its root-mean-square.
        double s2 = 0;
        for (double v : y) s2 += v * v;
        t.r = s2 > 0 ? my / std::sqrt(s2 / static_cast<double>(y.size())) : 0.0;
      } else {
        std::vector<double> x;
        for (size_t k : fit_idx) x.push_back(d.features[k].v.at(name));
        const double mx = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
        double sxx = 0, sxy = 0;
        for (size_t i = 0; i < x.size(); ++i) {
          sxx += (x[i] - mx) * (x[i] - mx);
          sxy += (x[i] - mx) * (y[i] - my);
        }
        t.r = (sxx > 0 && syy > 0) ? sxy / std::sqrt(sxx * syy) : 0.0;
      }
      t.z = t.r * std::sqrt(n_eff);
      out.push_back(t);
    }
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return std::abs(a.z) > std::abs(b.z); });
  return out;
}

ResidualTests Test(const Evaluation& e, double horizon) {
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

struct Fit {
  Eigen::VectorXd p;
  Eigen::MatrixXd cov_robust, cov_model, info;
  double cost = 0.0;
  double n_eff = 0.0;  // effective number of independent residuals
  bool ok = false;
};

Fit RunFit(const System& sys, const ControlSignal& u, const std::vector<PoseMeasurement>& meas,
           const Eigen::VectorXd& p0, bool covariance, int threads, int max_iterations = 60) {
  BatchOptions o;
  o.compute_covariance = false;
  o.profiled_covariance = covariance;
  o.max_iterations = max_iterations;
  o.num_threads = threads;
  Fit f;
  try {
    const BatchResult r = FitBatch(sys, u, meas, p0, o);
    f.p = r.params;
    f.cost = 2.0 * r.final_cost;
    f.ok = f.p.allFinite() && std::isfinite(f.cost);
    f.cov_robust = r.robust_covariance;
    f.cov_model = r.profiled_covariance;
    f.info = r.information;
    f.n_eff = r.effective_residuals;
  } catch (const std::exception&) {
    f.ok = false;
  }
  return f;
}

std::vector<ParamEstimate> Estimates(const System& sys, const Fit& f, int from, int to) {
  std::vector<ParamEstimate> out;
  for (int i = from; i < to; ++i) {
    const auto& pi = sys.params()[static_cast<size_t>(i)];
    ParamEstimate e{pi.name, pi.unit, f.p[i], NAN, NAN};
    if (f.cov_robust.rows() == f.p.size()) e.sigma = std::sqrt(std::max(0.0, f.cov_robust(i, i)));
    if (f.cov_model.rows() == f.p.size())
      e.sigma_model = std::sqrt(std::max(0.0, f.cov_model(i, i)));
    out.push_back(e);
  }
  return out;
}

// Parameters the information matrix cannot pin down.
std::vector<std::string> Unobservable(const System& sys, const Fit& f) {
  std::vector<std::string> msgs;
  const int np = static_cast<int>(f.p.size());
  if (f.info.rows() != np) return msgs;
  // Scale to relative units so that the test is unit free.
  Eigen::VectorXd s(np);
  for (int i = 0; i < np; ++i) {
    s[i] = std::max(std::abs(f.p[i]), sys.params()[static_cast<size_t>(i)].default_sigma);
  }
  const Eigen::MatrixXd I = s.asDiagonal() * f.info * s.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(I);
  const double top = std::max(es.eigenvalues().maxCoeff(), 1e-300);
  for (int k = 0; k < np; ++k) {
    if (es.eigenvalues()[k] > 1e-9 * top && es.eigenvalues()[k] > 1e-6) continue;
    const Eigen::VectorXd v = es.eigenvectors().col(k);
    int imax = 0;
    v.cwiseAbs().maxCoeff(&imax);
    const auto& pi = sys.params()[static_cast<size_t>(imax)];
    std::string msg = "parameter '" + pi.name + "' is not identifiable from this recording";
    std::string others;
    for (int i = 0; i < np; ++i) {
      if (i != imax && std::abs(v[i]) > 0.3 * std::abs(v[imax]))
        others += (others.empty() ? "" : ", ") + sys.params()[static_cast<size_t>(i)].name;
    }
    if (!others.empty()) msg += " (it trades off against " + others + ")";
    if (!pi.excitation.empty()) msg += "; excite it with " + pi.excitation;
    msgs.push_back(msg);
  }
  return msgs;
}

Eigen::VectorXd InitialParams(const System& sys, const std::map<std::string, double>& init) {
  Eigen::VectorXd p(sys.num_params());
  for (int i = 0; i < sys.num_params(); ++i)
    p[i] = sys.params()[static_cast<size_t>(i)].default_value;
  for (const auto& [name, v] : init) {
    const int i = sys.ParamIndex(name);
    if (i < 0) {
      std::string known;
      for (const auto& q : sys.params()) known += (known.empty() ? "" : ", ") + q.name;
      throw AnalysisError("--init: model '" + std::string(sys.model().name()) +
                          "' has no parameter '" + name + "' (its parameters: " + known + ")");
    }
    p[i] = v;
  }
  return p;
}

// Multi-start, staged fit of the bare model: short windows from many starts, then the best
// refined on full windows. Reports when distinct optima fit equally well.
Fit FitBaseline(const System& sys, const Dataset& d, const Eigen::VectorXd& p0,
                const AnalyzeOptions& o, FitReport* report) {
  const auto& u = d.rec->controls;
  const int np = sys.num_params();
  std::vector<Eigen::VectorXd> starts = {p0};
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto is_scale = [&](int i) {
    return sys.params()[static_cast<size_t>(i)].default_value != 0.0 && p0[i] != 0.0;
  };
  for (int i = 0; i < np; ++i) {
    for (double f : {0.2, 0.5, 2.0, 5.0}) {
      Eigen::VectorXd s = p0;
      if (is_scale(i)) {
        s[i] *= f;
      } else {
        s[i] += (f < 1.0 ? -1.0 : 1.0) * (f == 0.5 || f == 2.0 ? 1.0 : 3.0) *
                sys.params()[static_cast<size_t>(i)].default_sigma;
      }
      starts.push_back(s);
    }
  }
  for (int r = 0; r < 6; ++r) {
    Eigen::VectorXd s = p0;
    for (int i = 0; i < np; ++i) {
      if (is_scale(i)) {
        s[i] *= std::exp(std::log(5.0) * unit(rng));
      } else {
        s[i] += 2.0 * sys.params()[static_cast<size_t>(i)].default_sigma * gauss(rng);
      }
    }
    starts.push_back(s);
  }
  std::vector<Fit> stage1;
  for (size_t k = 0; k < starts.size(); ++k) {
    if (o.progress)
      o.progress(0.05 + 0.2 * static_cast<double>(k) / static_cast<double>(starts.size()),
                 "baseline: multi-start");
    Fit f = RunFit(sys, u, d.short_meas, starts[k], false, o.num_threads, 40);
    if (f.ok) stage1.push_back(std::move(f));
  }
  if (stage1.empty())
    throw AnalysisError(
        "baseline fit failed from every start: check that the controls drive the model (units, "
        "column order)");
  std::sort(stage1.begin(), stage1.end(),
            [](const Fit& a, const Fit& b) { return a.cost < b.cost; });
  // Refine the best few distinct optima on the full windows.
  std::vector<Fit> refined;
  for (size_t k = 0; k < stage1.size() && refined.size() < 3; ++k) {
    bool distinct = true;
    for (const auto& r : refined) {
      if (((stage1[k].p - r.p).array().abs() <= 1e-3 * (r.p.array().abs() + 1e-6)).all())
        distinct = false;
    }
    if (!distinct && k > 0) continue;
    if (stage1[k].cost > 1.5 * stage1[0].cost + 10.0) break;
    Fit f = RunFit(sys, u, d.fit_meas, stage1[k].p, true, o.num_threads);
    if (f.ok) refined.push_back(std::move(f));
  }
  if (refined.empty()) throw AnalysisError("baseline refinement failed");
  std::sort(refined.begin(), refined.end(),
            [](const Fit& a, const Fit& b) { return a.cost < b.cost; });
  Fit best = refined.front();
  report->unique = true;
  for (size_t k = 1; k < refined.size(); ++k) {
    const Fit& alt = refined[k];
    if (alt.cost > best.cost * 1.01 + 2.0) continue;  // clearly worse
    bool differs = false;
    for (int i = 0; i < np && best.cov_robust.rows() == np; ++i) {
      if (std::abs(alt.p[i] - best.p[i]) > 5.0 * std::sqrt(std::max(best.cov_robust(i, i), 1e-300)))
        differs = true;
    }
    if (differs) {
      report->unique = false;
      std::ostringstream m;
      m << "another optimum fits as well (cost " << alt.cost << " vs " << best.cost << "):";
      for (int i = 0; i < np; ++i)
        m << " " << sys.params()[static_cast<size_t>(i)].name << "=" << alt.p[i];
      report->uniqueness = m.str();
    }
  }
  return best;
}

// Candidate effect specs for a model.
std::vector<std::string> Candidates(const KinematicModel& m, const AnalyzeOptions& o) {
  if (o.effects_mode == "none") return {};
  if (o.effects_mode == "list") return o.effects;
  std::vector<std::string> out;
  for (const auto& name : EffectRegistry::Instance().Names()) {
    auto e = EffectRegistry::Instance().Create(name);
    if (!e->AppliesTo(m)) continue;
    std::string error;
    if (!e->Bind(m, {}, &error)) continue;
    out.push_back(name);
    // Channel-wise effects: also one candidate per channel.
    auto probe = EffectRegistry::Instance().Create(name);
    if (m.num_controls() > 1 && probe->Bind(m, {m.controls()[0].name}, &error)) {
      for (const auto& c : m.controls()) out.push_back(name + "[" + c.name + "]");
    }
  }
  return out;
}

FitReport MakeReport(const System& sys, const Fit& f, const Evaluation& e,
                     const std::vector<std::string>& effects, int fit_windows) {
  FitReport r;
  r.effects = effects;
  r.params = Estimates(sys, f, 0, sys.num_params());
  r.fit = e.fit;
  r.heldout = e.held;
  r.cost = f.cost;
  r.fit_windows = fit_windows;
  r.unobservable = Unobservable(sys, f);
  return r;
}

double SignatureZ(const Effect& e, const std::vector<DiagnosisTerm>& diag) {
  double z = 0.0;
  for (const auto& term : e.signature()) {
    const auto colon = term.find(':');
    const std::string comp = term.substr(0, colon), reg = term.substr(colon + 1);
    for (const auto& t : diag) {
      if (t.component == comp && t.regressor == reg) z = std::max(z, std::abs(t.z));
    }
  }
  return z;
}

}  // namespace

AnalyzeResult Analyze(const Recording& rec, const AnalyzeOptions& o) {
  std::string error;
  if (!o.IsValid(&error)) throw AnalysisError(error);
  AnalyzeResult res;
  res.model = o.model;
  res.source = rec.source;
  res.stats = rec.stats;
  res.warnings = rec.warnings;
  res.horizon_s = o.horizon_s;
  auto progress = [&](double f, const std::string& s) {
    if (o.progress) o.progress(f, s);
  };
  std::shared_ptr<const KinematicModel> model;
  try {
    model = MakeModel(o.model);
  } catch (const std::exception& e) {
    throw AnalysisError(e.what());
  }
  const System bare(model);
  const Eigen::VectorXd p0 = InitialParams(bare, o.init);  // rejects unknown names first
  Dataset d = Prepare(rec, o, &res.warnings);
  res.pose_sigma = d.sigma;
  res.pose_sigma_estimated = !o.pose_sigma.has_value();
  res.t_begin_s = std::max(d.t.front(), d.t_ctrl0);
  res.t_split_s = d.t_split;
  res.t_end_s = d.t.back();

  // 1. Baseline.
  progress(0.02, "baseline");
  FitReport base_report;
  Fit base = FitBaseline(bare, d, p0, o, &base_report);
  ComputeFeatures(&d, bare, base.p);
  const double command_lag = EstimateCommandLag(d, bare, base.p);
  Evaluation base_eval = Evaluate(bare, base.p, d);
  res.before = MakeReport(bare, base, base_eval, {}, static_cast<int>(d.fit_windows.size()));
  res.before.unique = base_report.unique;
  res.before.uniqueness = base_report.uniqueness;
  if (!res.before.unobservable.empty()) {
    std::string m = rec.source + ": ";
    for (const auto& s : res.before.unobservable) m += s + ". ";
    throw AnalysisError(m);
  }
  res.diagnosis_before = Diagnose(d, base_eval);
  res.tests_before = Test(base_eval, o.horizon_s);
  res.residual_steps.push_back({"before", base_eval.points});

  // 2. Selection.
  std::vector<std::string> accepted;
  std::vector<std::shared_ptr<const Effect>> accepted_effects;
  Fit current = base;
  Evaluation current_eval = base_eval;
  std::vector<DiagnosisTerm> diag = res.diagnosis_before;
  const auto candidates = Candidates(*model, o);
  const double nw = static_cast<double>(d.fit_windows.size());
  for (int round = 1; round <= o.max_effects && !candidates.empty(); ++round) {
    struct Tried {
      EffectTrial trial;
      Fit fit;
      Evaluation eval;
      std::vector<std::shared_ptr<const Effect>> effects;
      bool ok = false;
    };
    std::vector<Tried> tried;
    for (size_t c = 0; c < candidates.size(); ++c) {
      const std::string& spec = candidates[c];
      progress(0.3 + 0.6 *
                         ((round - 1) +
                          static_cast<double>(c) / static_cast<double>(candidates.size())) /
                         o.max_effects,
               "round " + std::to_string(round) + ": " + spec);
      if (std::find(accepted.begin(), accepted.end(), spec) != accepted.end()) continue;
      std::shared_ptr<const Effect> eff;
      std::vector<std::shared_ptr<const Effect>> effects = accepted_effects;
      try {
        eff = MakeEffect(ParseEffectSpec(spec), *model);
        effects.push_back(eff);
      } catch (const std::exception& e) {
        if (o.effects_mode == "list") throw AnalysisError(std::string("--effects: ") + e.what());
        continue;
      }
      std::unique_ptr<System> sys;
      try {
        sys = std::make_unique<System>(model, effects);
      } catch (const std::exception&) {
        continue;  // conflicts with an accepted effect (same parameters)
      }
      Tried t;
      t.trial.name = spec;
      t.trial.round = round;
      t.trial.signature_z = SignatureZ(*eff, diag);
      t.effects = effects;
      // Starts: current parameters plus the effect's defaults, and +-2 sigma for a single
      // new parameter (time offsets and lags can have several local optima).
      const int old_np = static_cast<int>(current.p.size());
      const int np = sys->num_params();
      Eigen::VectorXd s0(np);
      s0.head(old_np) = current.p;
      for (int i = old_np; i < np; ++i) s0[i] = sys->params()[static_cast<size_t>(i)].default_value;
      std::vector<Eigen::VectorXd> starts = {s0};
      if (np - old_np == 1 && (eff->stage() == EffectStage::kControlTiming ||
                               (eff->time_varying() && std::abs(command_lag) > 0.05))) {
        // Timing: start at the lag the cross-correlation found (a delay or a lag's tau).
        Eigen::VectorXd s = s0;
        s[np - 1] =
            eff->stage() == EffectStage::kControlTiming ? command_lag : std::abs(command_lag);
        starts.push_back(s);
      }
      if (np - old_np == 1) {
        for (double k : {-2.0, 2.0}) {
          Eigen::VectorXd s = s0;
          s[np - 1] += k * sys->params()[static_cast<size_t>(np - 1)].default_sigma;
          starts.push_back(s);
        }
      }
      Fit best;
      for (const auto& s : starts) {
        Fit f = RunFit(*sys, rec.controls, d.fit_meas, s, false, o.num_threads);
        if (f.ok && (!best.ok || f.cost < best.cost)) best = std::move(f);
      }
      if (!best.ok) continue;
      best = RunFit(*sys, rec.controls, d.fit_meas, best.p, true, o.num_threads, 20);
      if (!best.ok) continue;
      t.fit = best;
      t.eval = Evaluate(*sys, best.p, d);
      const int k = np - old_np;
      // Quasi-BIC: residuals within a window are correlated, so the sample size is the
      // effective number of independent residuals (AR(1) design effect of the larger
      // model, never fewer than one per window).
      const double n_eff = std::max(nw, best.n_eff);
      t.trial.delta_bic =
          n_eff * std::log(std::max(best.cost, 1e-300) / std::max(current.cost, 1e-300)) +
          k * std::log(n_eff);
      t.trial.heldout_gain =
          1.0 - t.eval.held.pos_rms_m / std::max(current_eval.held.pos_rms_m, 1e-300);
      t.trial.combined_gain = 1.0 - Combined(t.eval.held, d.sigma) /
                                        std::max(Combined(current_eval.held, d.sigma), 1e-300);
      t.trial.params = Estimates(*sys, best, old_np, np);
      const bool observable = Unobservable(*sys, best).empty();
      std::ostringstream ev;
      ev.precision(3);
      ev << "signature z=" << t.trial.signature_z << "; fit cost "
         << (best.cost / current.cost - 1.0) * 100.0 << " %, dBIC " << t.trial.delta_bic
         << "; held-out position RMS " << current_eval.held.pos_rms_m << " -> "
         << t.eval.held.pos_rms_m << " m, heading RMS " << current_eval.held.heading_rms_rad
         << " -> " << t.eval.held.heading_rms_rad << " rad";
      if (!observable) ev << "; not identifiable together with the model's parameters";
      t.trial.evidence = ev.str();
      t.ok = observable;
      tried.push_back(std::move(t));
    }
    // Best candidate: supported by the criterion and improving held-out error most.
    Tried* winner = nullptr;
    for (auto& t : tried) {
      if (!t.ok || t.trial.delta_bic >= 0.0 || t.trial.combined_gain < o.min_gain) continue;
      if (winner == nullptr || t.trial.combined_gain > winner->trial.combined_gain) winner = &t;
    }
    for (auto& t : tried) {
      if (&t == winner) t.trial.accepted = true;
      res.trials.push_back(t.trial);
    }
    if (winner == nullptr) break;
    accepted.push_back(winner->trial.name);
    accepted_effects = winner->effects;
    current = winner->fit;
    current_eval = winner->eval;
    diag = Diagnose(d, current_eval);
    res.residual_steps.push_back({"+" + winner->trial.name, current_eval.points});
  }
  progress(0.95, "report");
  const System final_sys(model, accepted_effects);
  res.after = MakeReport(final_sys, current, current_eval, accepted,
                         static_cast<int>(d.fit_windows.size()));
  res.diagnosis_after = diag;
  res.tests_after = Test(current_eval, o.horizon_s);
  progress(1.0, "done");
  return res;
}

}  // namespace kincal
