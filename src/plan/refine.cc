#include "plan/refine.h"

#include <algorithm>
#include <cmath>

#include "kincal/plan/design_information.h"
#include "plan/fleet.h"
#include "plan/greedy.h"

namespace kincal::plan_internal {
namespace {

// The largest sigma over its target among the scored parameters with one, after driving
// `u` on from `info` (the same controls before its time) to time t_s.
double WorstRatioAt(DesignInformation info, const PlanOptions& o, const ControlSignal& u,
                    double t_s) {
  info.Advance(t_s, u);
  return WorstTargetRatio(info.Covariance(), o);
}

// The time segments' controls (ControlsOfSegments) reach the targets, or the time they
// are at rest (they reach them no later than that, or never).
double TimeToTargets(const System& sys, const Eigen::VectorXd& params,
                     const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                     const std::vector<Values>& segments) {
  PlanOptions until = o;
  until.duration_s = std::min(o.duration_s, static_cast<double>(segments.size()) * o.segment_s +
                                                LongestStopSeconds(o, sys.num_controls()));
  Motion m;
  m.controls = ControlsOfSegments(segments, o, sys.num_controls());
  m.segment_starts_s = {0.0};
  EvaluateMotion(sys, params, prior_cov, ws, until, kCurveStepS, &m);
  return std::min(ReachedAt(m), until.duration_s);
}

// Whether the first n segments, then a stop, keep every robot within the prior inside
// (the planner's rule) until it has settled: what the greedy design checked of each
// segment, asked of the whole prefix.
bool PrefixStaysInside(const System& sys, const Eigen::VectorXd& params,
                       const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                       const std::vector<Values>& segments, size_t n) {
  const std::vector<Values> prefix(segments.begin(),
                                   segments.begin() + static_cast<std::ptrdiff_t>(n));
  PlanOptions until = o;
  until.duration_s = static_cast<double>(n) * o.segment_s +
                     LongestStopSeconds(o, sys.num_controls()) + o.segment_s + kSettleS;
  return FleetStaysInside(sys, params, prior_cov, ws, until,
                          ControlsOfSegments(prefix, until, sys.num_controls()));
}

}  // namespace

ControlSignal SegmentsDriven(const std::vector<Values>& segments, const PlanOptions& o,
                             int num_controls, Values* now) {
  ControlSignal u(num_controls, 0);
  *now = Values{};
  for (size_t k = 0; k < segments.size(); ++k) {
    const double t0 = static_cast<double>(k) * o.segment_s;
    AppendSlewed(&u, t0, t0 + o.segment_s, segments[k], o, now);
  }
  return u;
}

ControlSignal ControlsOfSegments(const std::vector<Values>& segments, const PlanOptions& o,
                                 int num_controls) {
  Values now{};
  ControlSignal u = SegmentsDriven(segments, o, num_controls, &now);
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
  size_t reach = segments->size();  // the last pass's: the segments it checked
  ControlSignal u = ControlsOfSegments(*segments, o, nc);  // the segments' controls, kept current
  for (int pass = 0; pass < passes; ++pass) {
    const double horizon = TimeToTargets(sys, params, prior_cov, ws, o, *segments);
    reach =
        std::min(segments->size(), static_cast<size_t>(std::ceil(horizon / o.segment_s - 1e-9)));
    // The information up to segment k's start: the same for every value tried there.
    DesignInformation before(sys, params, prior_cov, o.info);
    before.StartSegment(start, 0.0, u);
    double current = WorstRatioAt(before, o, u, horizon);
    int changed = 0;
    for (size_t k = 0; k < reach; ++k) {
      before.Advance(static_cast<double>(k) * o.segment_s, u);
      // Every value at segment k, best first; the best that keeps every robot inside is kept.
      std::vector<std::pair<double, size_t>> tried;
      for (size_t c = 0; c < grid.size(); ++c) {
        if (grid[c] == (*segments)[k]) continue;
        std::vector<Values> trial = *segments;
        trial[k] = grid[c];
        const double r = WorstRatioAt(before, o, ControlsOfSegments(trial, o, nc), horizon);
        if (r < current * (1.0 - 1e-6)) tried.emplace_back(r, c);
      }
      std::sort(tried.begin(), tried.end());
      for (const auto& [r, c] : tried) {
        std::vector<Values> trial = *segments;
        trial[k] = grid[c];
        if (!PrefixStaysInside(sys, params, prior_cov, ws, o, trial, reach)) continue;
        ControlSignal trial_u = ControlsOfSegments(trial, o, nc);
        current = r;
        *segments = std::move(trial);
        u = std::move(trial_u);
        ++changed;
        break;
      }
    }
    // A segment dropped: what follows it comes a segment sooner. Kept when the targets are
    // then reached a segment sooner and every robot stays inside.
    DesignInformation at_k(sys, params, prior_cov, o.info);
    at_k.StartSegment(start, 0.0, u);
    for (size_t k = 0; k < reach && reach > 1 && horizon > o.segment_s; ++k) {
      at_k.Advance(static_cast<double>(k) * o.segment_s, u);
      std::vector<Values> trial = *segments;
      trial.erase(trial.begin() + static_cast<std::ptrdiff_t>(k));
      ControlSignal trial_u = ControlsOfSegments(trial, o, nc);
      if (WorstRatioAt(at_k, o, trial_u, horizon - o.segment_s) > 1.0 ||
          !PrefixStaysInside(sys, params, prior_cov, ws, o, trial, reach - 1)) {
        continue;
      }
      *segments = std::move(trial);
      u = std::move(trial_u);
      --reach;
      ++changed;
      break;
    }
    kept += changed;
    if (changed == 0) break;
  }
  if (kept > 0) segments->resize(reach);
  return kept;
}

void DesignSoonest(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, Design* d) {
  const Eigen::VectorXd prior_sigma = prior_cov.diagonal().cwiseSqrt();
  std::vector<Design> designs;
  designs.push_back(std::move(*d));
  // The others: no longer than a couple of segments past the first (a design that needs
  // more is not the soonest).
  const int most = static_cast<int>(designs[0].chosen.size()) + 2;
  for (DesignCriterion c : {DesignCriterion::kTargets, DesignCriterion::kD, DesignCriterion::kA}) {
    if (c == o.criterion) continue;
    PlanOptions other = o;
    other.criterion = c;
    Design e = DesignAtStart(sys, params, prior_cov, ws, o);
    if (DesignSegments(sys, ws, other, grid, prior_sigma, most, true, &e) &&
        WorstTargetRatio(e.info.Covariance(), o) <= 1.0) {
      designs.push_back(std::move(e));
    }
  }
  // Each as designed (a Design ready to go on from) and refined (its segments), soonest
  // first; a refined one goes on from a Design made by driving its segments, which checks
  // every robot within the prior once more along them and a stop after them.
  const int nc = sys.num_controls();
  struct Option {
    double t;
    size_t design;
    std::vector<Values> refined;  // empty: the design as it is
  };
  std::vector<Option> options;
  for (size_t k = 0; k < designs.size(); ++k) {
    options.push_back({TimeToTargets(sys, params, prior_cov, ws, o, designs[k].chosen), k, {}});
  }
  const auto sooner = [](const Option& a, const Option& b) { return a.t < b.t; };
  std::stable_sort(options.begin(), options.end(), sooner);
  // Refined soonest first; one that was designed slower than the soonest so far is left
  // (refining gains some 10 %: it would not be the soonest, and refining costs most here).
  double soonest = options.front().t;
  for (size_t k = 0, n = options.size(); k < n && options[k].t <= soonest; ++k) {
    std::vector<Values> refined = designs[options[k].design].chosen;
    if (RefineSegments(sys, params, prior_cov, ws, o, grid, o.refine_passes, &refined) > 0) {
      const double t = TimeToTargets(sys, params, prior_cov, ws, o, refined);
      soonest = std::min(soonest, t);
      options.push_back({t, options[k].design, std::move(refined)});
    }
  }
  std::stable_sort(options.begin(), options.end(), sooner);
  for (Option& option : options) {
    if (option.refined.empty()) {
      *d = std::move(designs[option.design]);
      return;
    }
    Values now{};
    const ControlSignal prefix = SegmentsDriven(option.refined, o, nc, &now);
    Design b = DesignAtStart(sys, params, prior_cov, ws, o);
    if (DesignFromSeed(sys, ws, o, prefix, static_cast<double>(option.refined.size()) * o.segment_s,
                       &b)) {
      b.chosen = std::move(option.refined);
      *d = std::move(b);
      return;
    }
  }
}

}  // namespace kincal::plan_internal
