#include "analysis/runs.h"

#include <algorithm>
#include <cmath>

#include "kincal/angles.h"

namespace kincal::analysis {
namespace {

// [first, last] pose indices of each run (by_runs), or of the held-out span (one run).
std::vector<std::pair<int, int>> Spans(const Dataset& d, bool heldout_only) {
  std::vector<std::pair<int, int>> spans;
  const int n = static_cast<int>(d.t.size());
  if (!d.by_runs) {
    const int first =
        static_cast<int>(std::lower_bound(d.t.begin(), d.t.end(), d.t_split) - d.t.begin());
    if (first < n - 1) spans.emplace_back(first, n - 1);
    return spans;
  }
  for (int i = 0; i < n;) {
    int j = i;
    while (j + 1 < n && d.run[static_cast<size_t>(j + 1)] == d.run[static_cast<size_t>(i)]) ++j;
    const bool held = d.run_heldout[static_cast<size_t>(d.run[static_cast<size_t>(i)])];
    if (j > i && (held || !heldout_only)) spans.emplace_back(i, j);
    i = j + 1;
  }
  return spans;
}

// Poses before the first control are not predicted (the robot's commands are unknown).
int FirstControlled(const Dataset& d, int first, int last) {
  while (first < last && d.t[static_cast<size_t>(first)] < d.t_ctrl0) ++first;
  return first;
}

}  // namespace

DeadReckoning DeadReckon(const System& sys, const Eigen::VectorXd& p, const Dataset& d, int first,
                         int last) {
  DeadReckoning r;
  first = FirstControlled(d, first, last);
  if (last <= first) return r;
  const auto& u = d.rec->controls;
  const auto& poses = d.rec->poses;
  double t = d.t[static_cast<size_t>(first)];
  StateVec x = sys.MakeState(0, 0, 0, p, u, t);
  sys.SetPoseFromMeasurement(poses[static_cast<size_t>(first)].z.data(), x.data());
  double sum = 0.0, z[3] = {0, 0, 0};
  for (int k = first + 1; k <= last; ++k) {
    const double tk = d.t[static_cast<size_t>(k)];
    sys.Propagate(x.data(), x.data(), t, tk, u, static_cast<const double*>(nullptr));
    t = tk;
    sys.Measure(x.data(), z);
    const Eigen::Vector3d& m = poses[static_cast<size_t>(k)].z;
    sum += (m.head<2>() - Eigen::Vector2d(z[0], z[1])).squaredNorm();
  }
  const Eigen::Vector3d& end = poses[static_cast<size_t>(last)].z;
  r.duration_s = d.t[static_cast<size_t>(last)] - d.t[static_cast<size_t>(first)];
  r.rms_m = std::sqrt(sum / (last - first));
  r.final_m = (end.head<2>() - Eigen::Vector2d(z[0], z[1])).norm();
  r.final_rad = std::abs(WrapAngle(end.z() - z[2]));
  r.runs = 1;
  return r;
}

std::vector<RunReport> PerRun(const Dataset& d, const Evaluation& before, const Evaluation& after,
                              const System& before_sys, const Eigen::VectorXd& before_p,
                              const System& after_sys, const Eigen::VectorXd& after_p) {
  std::vector<RunReport> out;
  if (!d.by_runs) return out;
  out.resize(d.run_start_s.size());
  for (size_t r = 0; r < out.size(); ++r) {
    out[r].index = static_cast<int>(r) + 1;
    out[r].source = d.rec->runs[r].source;
    out[r].heldout = d.run_heldout[r];
  }
  // Evaluation points are in window order: d.eval[k] is points[k].
  for (size_t k = 0; k < d.eval.size() && k < before.points.size() && k < after.points.size();
       ++k) {
    RunReport& rr = out[static_cast<size_t>(d.run[static_cast<size_t>(d.eval[k].start)])];
    const ResidualPoint &b = before.points[k], &a = after.points[k];
    ++rr.windows;
    rr.before_pos_rms_m += b.along * b.along + b.cross * b.cross;
    rr.after_pos_rms_m += a.along * a.along + a.cross * a.cross;
    rr.before_heading_rms_rad += b.heading * b.heading;
    rr.after_heading_rms_rad += a.heading * a.heading;
  }
  for (auto& rr : out) {
    const double n = std::max(1, rr.windows);
    for (double* v : {&rr.before_pos_rms_m, &rr.after_pos_rms_m, &rr.before_heading_rms_rad,
                      &rr.after_heading_rms_rad})
      *v = std::sqrt(*v / n);
  }
  for (const auto& [first, last] : Spans(d, false)) {
    RunReport& rr = out[static_cast<size_t>(d.run[static_cast<size_t>(first)])];
    rr.dr_before = DeadReckon(before_sys, before_p, d, first, last);
    rr.dr_after = DeadReckon(after_sys, after_p, d, first, last);
  }
  return out;
}

DeadReckoning HeldOutDeadReckoning(const System& sys, const Eigen::VectorXd& p, const Dataset& d) {
  DeadReckoning pooled;
  double rms2 = 0.0, fm2 = 0.0, fr2 = 0.0;
  for (const auto& [first, last] : Spans(d, true)) {
    const DeadReckoning r = DeadReckon(sys, p, d, first, last);
    if (r.runs == 0) continue;
    pooled.duration_s += r.duration_s;
    rms2 += r.rms_m * r.rms_m;
    fm2 += r.final_m * r.final_m;
    fr2 += r.final_rad * r.final_rad;
    ++pooled.runs;
  }
  if (pooled.runs == 0) return pooled;
  pooled.rms_m = std::sqrt(rms2 / pooled.runs);
  pooled.final_m = std::sqrt(fm2 / pooled.runs);
  pooled.final_rad = std::sqrt(fr2 / pooled.runs);
  return pooled;
}

}  // namespace kincal::analysis
