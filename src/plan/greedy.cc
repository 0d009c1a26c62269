#include "plan/greedy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace kincal::plan_internal {
namespace {

constexpr double kAnticipateS = 1.0;  // the most negative delay driven exactly (s)

// Whether `fleet` (driven along u so far) keeps inside along u to t_s, where u is at
// `at`, and a stop from there: until every robot within the prior has come to rest (a lag
// or a delay at the prior's 3 sigma keeps one moving for a while).
bool StopsInside(const System& sys, const Workspace& ws, const PlanOptions& o,
                 const ControlSignal& u, const Values& at, double t_s, Fleet fleet) {
  ControlSignal braked = u;
  Values b = at;
  const double settle = t_s + o.segment_s + kSettleS;
  AppendSlewed(&braked, t_s, settle, Values{}, o, &b);
  return DriveFleet(sys, braked, ws, settle, kFleetCheckS, true, &fleet);
}

}  // namespace

std::optional<Trial> TryCandidate(const System& sys, const Workspace& ws, const PlanOptions& o,
                                  const Eigen::VectorXd& prior_sigma, const Values& cand,
                                  const Design& d) {
  ControlSignal u = d.u;
  Values at = d.now;
  const double t1 = d.t_s + o.segment_s;
  AppendSlewed(&u, d.t_s, t1, cand, o, &at);
  if (!StopsInside(sys, ws, o, u, at, t1, d.fleet)) return std::nullopt;
  DesignInformation info = d.info;
  info.Advance(t1, u);
  const double score = DesignScore(info.Covariance(), prior_sigma, o);
  return Trial{score, std::move(u), at, std::move(info), cand};
}

void KeepTrial(const System& sys, const Workspace& ws, const PlanOptions& o, Trial* t, Design* d) {
  d->u = std::move(t->u);
  d->chosen.push_back(t->value);
  d->now = t->end;
  d->info = std::move(t->info);
  d->t_s += o.segment_s;
  // The fleet stays kAnticipateS behind the plan: a robot with a negative delay (a
  // camera clock behind the robot's) moves by commands not yet chosen, and is driven
  // through them only when they are.
  DriveFleet(sys, d->u, ws, std::max(0.0, d->t_s - kAnticipateS), kFleetCheckS, false, &d->fleet);
}

Design DesignAtStart(const System& sys, const Eigen::VectorXd& params,
                     const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o) {
  const Eigen::Vector3d start = StartPose(ws, o);
  Design d{ControlSignal(sys.num_controls(), 0),
           Values{},
           DesignInformation(sys, params, prior_cov, o.info),
           Fleet{},
           0.0,
           {}};
  d.info.StartSegment(start, 0.0, d.u);
  d.fleet = FleetAtStart(sys, params, prior_cov, start, o, d.u);
  return d;
}

bool DesignFromSeed(const System& sys, const Workspace& ws, const PlanOptions& o,
                    const ControlSignal& seed, double seed_s, Design* d) {
  AppendSamplesBefore(&d->u, seed, seed_s);
  d->now = seed.At(seed_s);
  d->t_s = seed_s;
  d->info.Advance(seed_s, d->u);
  // A stop from the seed's end must keep every robot inside too (as each segment's does).
  if (!StopsInside(sys, ws, o, d->u, d->now, seed_s, d->fleet)) return false;
  return DriveFleet(sys, d->u, ws, std::max(0.0, seed_s - kAnticipateS), kFleetCheckS, true,
                    &d->fleet);
}

bool DesignSegments(const System& sys, const Workspace& ws, const PlanOptions& o,
                    const std::vector<Values>& grid, const Eigen::VectorXd& prior_sigma, int count,
                    bool until_targets, Design* d) {
  for (int s = 0; s < count; ++s) {
    if (until_targets && WorstTargetRatio(d->info.Covariance(), o) <= 1.0) return true;
    std::optional<Trial> best;
    for (const Values& cand : grid) {
      std::optional<Trial> t = TryCandidate(sys, ws, o, prior_sigma, cand, *d);
      if (t && (!best || t->score < best->score)) best = std::move(t);
    }
    if (!best) return false;
    KeepTrial(sys, ws, o, &*best, d);
  }
  return true;
}

double WorstTargetRatio(const Eigen::MatrixXd& cov, const PlanOptions& o) {
  if (o.targets.size() == 0) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (int i : ScoredParams(o, static_cast<int>(cov.rows()))) {
    if (o.targets[i] > 0.0) worst = std::max(worst, std::sqrt(cov(i, i)) / o.targets[i]);
  }
  return worst;
}

}  // namespace kincal::plan_internal
