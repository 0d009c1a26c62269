#include "plan/refine.h"

#include <algorithm>
#include <cmath>

#include "kincal/plan/design_information.h"
#include "plan/fleet.h"

namespace kincal::plan_internal {
namespace {

// The largest sigma over its target among the scored parameters with one, after driving
// `u` on from `info` (the same controls before its time) to time t_s.
double WorstRatioAt(const System& sys, DesignInformation info, const PlanOptions& o,
                    const ControlSignal& u, double t_s) {
  info.Advance(t_s, u);
  const Eigen::VectorXd sigma = info.Covariance().diagonal().cwiseSqrt();
  double worst = 0.0;
  for (int i : ScoredParams(o, sys.num_params())) {
    if (o.targets[i] > 0.0) worst = std::max(worst, sigma[i] / o.targets[i]);
  }
  return worst;
}

// The time the whole plan reaches the targets (its sigma curve), or the duration.
double TimeToTargets(const System& sys, const Eigen::VectorXd& params,
                     const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                     const ControlSignal& u) {
  Motion m;
  m.controls = u;
  m.segment_starts_s = {0.0};
  EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, &m);
  const double t = m.curve.time_to_target_s;
  return std::isfinite(t) && !m.curve.extrapolated ? std::min(t, o.duration_s) : o.duration_s;
}

}  // namespace

ControlSignal ControlsOfSegments(const std::vector<Values>& segments, const PlanOptions& o,
                                 int num_controls) {
  ControlSignal u(num_controls, 0);
  Values now{};
  for (size_t k = 0; k < segments.size(); ++k) {
    const double t0 = static_cast<double>(k) * o.segment_s;
    AppendSlewed(&u, t0, t0 + o.segment_s, segments[k], o, &now);
  }
  AppendStopAndRest(&u, static_cast<double>(segments.size()) * o.segment_s, o.duration_s, o, &now);
  return u;
}

int RefineSegments(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, int passes, std::vector<Values>* segments) {
  if (o.targets.size() == 0 || segments->empty()) return 0;
  const int nc = sys.num_controls();
  const Eigen::Vector3d start = StartPose(ws, o);
  int kept = 0;
  ControlSignal u = ControlsOfSegments(*segments, o, nc);  // the segments' controls, kept current
  for (int pass = 0; pass < passes; ++pass) {
    const double horizon = TimeToTargets(sys, params, prior_cov, ws, o, u);
    const size_t reach =
        std::min(segments->size(), static_cast<size_t>(std::ceil(horizon / o.segment_s - 1e-9)));
    // The information up to segment k's start: the same for every value tried there.
    DesignInformation before(sys, params, prior_cov, o.info);
    before.StartSegment(start, 0.0, u);
    double current = WorstRatioAt(sys, before, o, u, horizon);
    int changed = 0;
    for (size_t k = 0; k < reach; ++k) {
      before.Advance(static_cast<double>(k) * o.segment_s, u);
      // Every value at segment k, best first; the best that keeps every robot inside is kept.
      std::vector<std::pair<double, size_t>> tried;
      for (size_t c = 0; c < grid.size(); ++c) {
        if (grid[c] == (*segments)[k]) continue;
        std::vector<Values> trial = *segments;
        trial[k] = grid[c];
        const double r = WorstRatioAt(sys, before, o, ControlsOfSegments(trial, o, nc), horizon);
        if (r < current * (1.0 - 1e-6)) tried.emplace_back(r, c);
      }
      std::sort(tried.begin(), tried.end());
      for (const auto& [r, c] : tried) {
        std::vector<Values> trial = *segments;
        trial[k] = grid[c];
        ControlSignal trial_u = ControlsOfSegments(trial, o, nc);
        if (!FleetStaysInside(sys, params, prior_cov, ws, o, trial_u)) continue;
        current = r;
        *segments = std::move(trial);
        u = std::move(trial_u);
        ++changed;
        break;
      }
    }
    kept += changed;
    if (changed == 0) break;
  }
  return kept;
}

}  // namespace kincal::plan_internal
