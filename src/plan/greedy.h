// Greedy sequential design: from a motion so far, one segment at a time, every candidate
// control of the grid driven for a segment (and a stop after it, for every robot within
// the prior), the best-scoring one kept.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "kincal/plan/design_information.h"
#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"
#include "plan/fleet.h"
#include "plan/shaping.h"

namespace kincal::plan_internal {

inline constexpr double kSettleS = 3.0;  // a stop is followed this long beyond its slewing (s)

// A design under way: its controls so far (the next segment starts at t_s), the values
// they end at, what is then known, the prior's fleet (kept kAnticipateS behind t_s) and the
// segments chosen so far.
struct Design {
  ControlSignal u;
  Values now{};
  DesignInformation info;
  Fleet fleet;
  double t_s = 0.0;
  std::vector<Values> chosen;
};

// The design at rest at the start pose, nothing driven.
Design DesignAtStart(const System& sys, const Eigen::VectorXd& params,
                     const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o);

// Drives `seed`'s controls until seed_s (a usual motion's start) from `d`, a design at its
// start (DesignAtStart): false when a robot within the prior leaves the workspace on the
// way or in a stop from there (the planner's rule).
bool DesignFromSeed(const System& sys, const Workspace& ws, const PlanOptions& o,
                    const ControlSignal& seed, double seed_s, Design* d);

// One candidate control driven for a segment from `d`: its controls, where they end, what
// is then known at the design point and its DesignScore.
struct Trial {
  double score;
  ControlSignal u;
  Values end;
  DesignInformation info;
  Values value;  // the segment's control
};

// Tries candidate `cand`: drives it for a segment from d and a stop after it. Nothing when
// a robot within the prior would leave the workspace on the way or in the stop.
std::optional<Trial> TryCandidate(const System& sys, const Workspace& ws, const PlanOptions& o,
                                  const Eigen::VectorXd& prior_sigma, const Values& cand,
                                  const Design& d);

// Makes trial `t` (from TryCandidate on d) d's next segment.
void KeepTrial(const System& sys, const Workspace& ws, const PlanOptions& o, Trial* t, Design* d);

// Up to `count` greedy segments from d->t_s (with `until_targets`, no more once the targets
// are reached). False when no candidate keeps every robot within the prior inside; `d` then
// ends at the segment that found none.
bool DesignSegments(const System& sys, const Workspace& ws, const PlanOptions& o,
                    const std::vector<Values>& grid, const Eigen::VectorXd& prior_sigma, int count,
                    bool until_targets, Design* d);

// The largest sigma over its target among the scored parameters with one, from `cov`.
double WorstTargetRatio(const Eigen::MatrixXd& cov, const PlanOptions& o);

}  // namespace kincal::plan_internal
