// Looking further than one segment: a greedy plan refined by coordinate descent on its
// segments' controls, each change judged by the whole plan's standing at the time the
// targets are reached (the greedy choice judged only the next segment).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"
#include "plan/shaping.h"

namespace kincal::plan_internal {

// The plan's controls from its segments' values: each slewed to for a segment from the
// last, from rest, then the stop and rest by o.duration_s (as PlanMotion builds them).
ControlSignal ControlsOfSegments(const std::vector<Values>& segments, const PlanOptions& o,
                                 int num_controls);

// With targets: passes over the segments before the time the targets are reached, each
// segment tried at every value of `grid`; a change is kept when it lowers the largest
// sigma-over-target at that time and every robot within the prior still keeps inside
// (FleetStaysInside on the whole plan). Up to `passes` passes, fewer when one changes
// nothing. Returns the changes kept. Without targets, nothing is done.
int RefineSegments(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, int passes, std::vector<Values>* segments);

}  // namespace kincal::plan_internal
