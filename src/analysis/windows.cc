#include "analysis/windows.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kincal/angles.h"

namespace kincal::analysis {
namespace {

// What cutting the recording throws when it is unusable; caught in Prepare, which returns
// it as a Status.
class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A window whose horizon end lands more than this fraction of the horizon (plus 1 ms)
// past the nearest pose spans a gap and is not used.
constexpr double kMaxEndOvershoot = 0.1;
// A window's end may also miss its target time by half a typical pose interval: at low pose
// rates (2-5 Hz) no pose lies within a tenth of a horizon of most targets.
constexpr double kEndToleranceIntervals = 0.5;
// The multi-start stage's short windows: a quarter horizon and at least two typical pose
// intervals, at least 0.2 s, at most 150.
constexpr double kShortWindowFraction = 0.25;
constexpr double kShortWindowIntervals = 2.0;
constexpr double kMinShortWindowS = 0.2;
constexpr int kMaxShortWindows = 150;
// Screening subsamples the fit windows only when each screening set keeps this many.
constexpr int kMinScreenWindows = 12;
// The fewest poses a recording must have.
constexpr size_t kMinPoses = 20;
// No window spans a gap between consecutive poses longer than this many typical pose
// intervals and this fraction of the horizon: the robot may have been carried (kidnapped)
// or lost there, and nothing predicts across it.
constexpr double kInnerGapIntervals = 3.0;
constexpr double kInnerGapHorizonFraction = 0.25;

// The median interval between consecutive poses, s.
double MedianInterval(const std::vector<double>& t) {
  std::vector<double> dt;
  for (size_t i = 1; i < t.size(); ++i) dt.push_back(t[i] - t[i - 1]);
  if (dt.empty()) return 0.0;
  auto mid = dt.begin() + static_cast<long>(dt.size() / 2);
  std::nth_element(dt.begin(), mid, dt.end());
  return *mid;
}

// For each pose, the index of the first pose after which a gap (or a new run) follows
// (n - 1 if none).
std::vector<int> NextGap(const std::vector<double>& t, const std::vector<int>& run, double median,
                         double h) {
  const size_t n = t.size();
  const double limit = std::max(kInnerGapIntervals * median, kInnerGapHorizonFraction * h);
  std::vector<int> next(n, static_cast<int>(n) - 1);
  for (size_t k = n - 1; k-- > 0;) {
    const bool new_run = !run.empty() && run[k + 1] != run[k];
    next[k] = new_run || t[k + 1] - t[k] > limit ? static_cast<int>(k) : next[k + 1];
  }
  return next;
}

// Runs: each pose's run, and which runs are held out (AnalyzeOptions::heldout_runs, or
// every third). Only for a recording of two or more runs.
void SetRuns(const Recording& rec, const AnalyzeOptions& o, Dataset* d) {
  const int n = static_cast<int>(rec.runs.size());
  if (n < 2) {
    if (!o.heldout_runs.empty())
      throw DataError(rec.source + ": --heldout-runs: the recording is one run");
    return;
  }
  d->by_runs = true;
  for (const auto& r : rec.runs) {
    d->run_start_s.push_back(rec.controls.ToSeconds(r.start_ns));
    d->limits.run_starts.push_back(r.start_ns);
  }
  for (const auto& p : rec.poses) d->run.push_back(RunOf(rec, p.t_ns));
  d->run_heldout.assign(static_cast<size_t>(n), false);
  for (int k : o.heldout_runs) {
    if (k < 1 || k > n) {
      throw DataError(rec.source + ": --heldout-runs: no run " + std::to_string(k) +
                      " (the recording has runs 1.." + std::to_string(n) + ")");
    }
    d->run_heldout[static_cast<size_t>(k - 1)] = true;
  }
  if (o.heldout_runs.empty()) {
    for (int r = 0; r < n; ++r)
      d->run_heldout[static_cast<size_t>(r)] = n == 2 ? r == 1 : r % 3 == 2;
  }
  if (std::all_of(d->run_heldout.begin(), d->run_heldout.end(), [](bool h) { return h; }))
    throw DataError(rec.source + ": --heldout-runs holds out every run; none is left to fit");
}

int FindEnd(const Dataset& d, int i, double h) {
  const auto& t = d.t;
  const double target = t[static_cast<size_t>(i)] + h;
  const auto it = std::lower_bound(t.begin() + i, t.end(), target - 1e-9);
  if (it == t.end()) return -1;
  const int j = static_cast<int>(it - t.begin());
  const double tolerance =
      std::max(kMaxEndOvershoot * h, kEndToleranceIntervals * d.pose_interval) + 1e-3;
  if (t[static_cast<size_t>(j)] - target > tolerance) return -1;  // a gap
  if (d.next_gap[static_cast<size_t>(i)] < j) return -1;          // a gap inside
  return j;
}

// Non-overlapping windows of h seconds in [t0, t1] outside the held-out runs.
std::vector<Window> NonOverlapping(const Dataset& d, double h, double t0, double t1, int max_n) {
  std::vector<Window> w;
  const auto& t = d.t;
  int i = static_cast<int>(std::lower_bound(t.begin(), t.end(), t0) - t.begin());
  while (i < static_cast<int>(t.size()) && t[static_cast<size_t>(i)] + h <= t1) {
    const int j = d.by_runs && d.HeldOutAt(t[static_cast<size_t>(i)]) ? -1 : FindEnd(d, i, h);
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

// Runs without a single evaluation window (shorter than one horizon): skipped, and said.
void CountShortRuns(const Dataset& d, std::vector<std::string>* warnings) {
  if (!d.by_runs) return;
  std::vector<int> windows(d.run_start_s.size(), 0);
  for (const auto& w : d.eval) ++windows[static_cast<size_t>(d.run[static_cast<size_t>(w.start)])];
  std::string which;
  int skipped = 0;
  for (size_t r = 0; r < windows.size(); ++r) {
    if (windows[r] > 0) continue;
    ++skipped;
    which += (which.empty() ? "" : ", ") + std::to_string(r + 1);
  }
  if (skipped == static_cast<int>(windows.size())) {
    throw DataError(d.rec->source + ": every run is shorter than one prediction window (" +
                    std::to_string(d.horizon) + " s); lower --horizon");
  }
  if (skipped > 0) {
    warnings->push_back(std::to_string(skipped) + " run(s) shorter than one prediction window (" +
                        std::to_string(d.horizon) + " s) skipped: run " + which);
  }
}

// Evaluation windows from (strided) measured poses in [t0, t1]; none straddles the split.
std::vector<Window> EvaluationWindows(const Dataset& d, double t0, double t1, int max_n) {
  std::vector<Window> out;
  const int first = static_cast<int>(std::lower_bound(d.t.begin(), d.t.end(), t0) - d.t.begin());
  const int n = static_cast<int>(d.t.size());
  const int stride = std::max(1, (n - first) / max_n);
  for (int i = first; i < n; i += stride) {
    const int j = FindEnd(d, i, d.horizon);
    if (j < 0 || d.t[static_cast<size_t>(j)] > t1) continue;
    const bool held = d.HeldOutAt(d.t[static_cast<size_t>(i)]);
    const bool fit = d.by_runs ? !held : d.t[static_cast<size_t>(j)] <= d.t_split;
    if (fit || held) out.push_back({i, j});
  }
  return out;
}

}  // namespace

bool Dataset::HeldOutAt(double t_s) const {
  if (!by_runs) return t_s >= t_split;
  const auto it = std::upper_bound(run_start_s.begin(), run_start_s.end(), t_s);
  const size_t r =
      it == run_start_s.begin() ? 0 : static_cast<size_t>(it - run_start_s.begin()) - 1;
  return run_heldout[r];
}

namespace {

// Why there are too few fit windows. Poses farther apart than a horizon are most often a
// time column in milliseconds (or nanoseconds, for a recording of a few seconds).
std::string FewFitWindows(const Recording& rec, const Dataset& d) {
  if (d.pose_interval > d.horizon) {
    std::ostringstream m;
    m << rec.source << ": the poses are " << d.pose_interval
      << " s apart (the median), more than the horizon of " << d.horizon
      << " s: is 't' in seconds? (times in milliseconds or nanoseconds look like this; "
         "otherwise raise --horizon)";
    return m.str();
  }
  return rec.source +
         ": fewer than 5 prediction windows in the fit part (gaps, or a recording shorter than a "
         "few horizons)";
}

Dataset PrepareOrThrow(const Recording& rec, const AnalyzeOptions& o,
                       std::vector<std::string>* warnings) {
  Dataset d;
  d.rec = &rec;
  d.horizon = o.horizon_s;
  if (rec.poses.size() < kMinPoses)
    throw DataError(rec.source + ": only " + std::to_string(rec.poses.size()) +
                    " poses; at least " + std::to_string(kMinPoses) + " are needed");
  if (rec.controls.size() < 2) throw DataError(rec.source + ": fewer than 2 control samples");
  for (const auto& p : rec.poses) d.t.push_back(rec.controls.ToSeconds(p.t_ns));
  d.t_ctrl0 = rec.controls.TimeAt(0);
  d.t_ctrl1 = rec.controls.TimeAt(static_cast<int>(rec.controls.size()) - 1);
  const double t0 = std::max(d.t.front(), d.t_ctrl0);
  const double t1 = std::min(d.t.back(), d.t_ctrl1 + o.horizon_s);
  if (t1 - t0 < 4.0 * o.horizon_s) {
    std::ostringstream m;
    m << rec.source << ": controls and poses overlap for only " << std::max(0.0, t1 - t0)
      << " s; at least 4 horizons (" << 4.0 * o.horizon_s << " s) are needed";
    throw DataError(m.str());
  }
  if (d.t_ctrl0 > d.t.front() + 1.0) {
    std::ostringstream m;
    m << "poses start " << d.t_ctrl0 - d.t.front()
      << " s before the first control; that part is not used";
    warnings->push_back(m.str());
  }
  SetRuns(rec, o, &d);
  d.t_split = d.by_runs ? t1 : t0 + o.fit_fraction * (t1 - t0);
  d.pose_interval = MedianInterval(d.t);
  d.next_gap = NextGap(d.t, d.run, d.pose_interval, o.horizon_s);
  d.sigma = o.pose_sigma ? *o.pose_sigma : EstimatePoseSigma(rec);
  d.R = Eigen::Vector3d(d.sigma[0] * d.sigma[0], d.sigma[0] * d.sigma[0], d.sigma[1] * d.sigma[1])
            .asDiagonal();
  d.eval = EvaluationWindows(d, t0, t1, o.max_eval_windows);
  CountShortRuns(d, warnings);
  d.fit_windows = NonOverlapping(d, o.horizon_s, t0, d.t_split, o.max_fit_windows);
  const double hs = std::max({kMinShortWindowS, kShortWindowFraction * o.horizon_s,
                              kShortWindowIntervals * d.pose_interval});
  d.short_windows =
      NonOverlapping(d, hs, t0, d.t_split, std::min(kMaxShortWindows, o.max_fit_windows));
  if (d.fit_windows.size() < 5) throw DataError(FewFitWindows(rec, d));
  int held = 0;
  for (const auto& w : d.eval) held += d.HeldOutAt(d.t[static_cast<size_t>(w.start)]);
  if (held < 5)
    throw DataError(rec.source + ": fewer than 5 prediction windows in the held-out part; " +
                    (d.by_runs ? "hold out other runs (--heldout-runs) or lower --horizon"
                               : "lower --fit-fraction or --horizon"));
  d.fit_meas = WindowMeasurements(d, d.fit_windows, o.poses_per_window);
  d.short_meas = WindowMeasurements(d, d.short_windows, std::max(2, o.poses_per_window / 2));
  d.screen_meas = d.fit_meas;
  if (o.screen_stride > 1 &&
      d.fit_windows.size() >= static_cast<size_t>(kMinScreenWindows * o.screen_stride)) {
    std::vector<Window> every;
    for (size_t k = 0; k < d.fit_windows.size(); k += static_cast<size_t>(o.screen_stride))
      every.push_back(d.fit_windows[k]);
    d.screen_meas = WindowMeasurements(d, every, o.poses_per_window);
  }
  return d;
}

}  // namespace

StatusOr<Dataset> Prepare(const Recording& rec, const AnalyzeOptions& o,
                          std::vector<std::string>* warnings) {
  try {
    return PrepareOrThrow(rec, o, warnings);
  } catch (const DataError& e) {
    return Status::Error(e.what());
  }
}

}  // namespace kincal::analysis
