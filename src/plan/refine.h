// Looking further than one segment: a greedy plan refined by coordinate descent on its
// segments' controls, each change judged by the whole plan's standing at the time the
// targets are reached (the greedy choice judged only the next segment).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"
#include "plan/greedy.h"
#include "plan/shaping.h"

namespace kincal::plan_internal {

// The plan's controls from its segments' values: each slewed to for a segment from the
// last, from rest, then the stop and rest by o.duration_s (as PlanMotion builds them).
ControlSignal ControlsOfSegments(const std::vector<Values>& segments, const PlanOptions& o,
                                 int num_controls);

// The segments' controls alone, from rest (no stop); *now ends at their last value.
ControlSignal SegmentsDriven(const std::vector<Values>& segments, const PlanOptions& o,
                             int num_controls, Values* now);

// With targets: passes over the segments before the time the targets are reached, each
// segment tried at every value of `grid`; a change is kept when it lowers the largest
// sigma-over-target at that time and every robot within the prior still keeps inside
// along those segments and a stop after them (FleetStaysInside, the planner's rule); then
// each segment is tried dropped (what follows comes a segment sooner), kept when the
// targets are then reached a segment sooner and every robot still keeps inside. Up to
// `passes` passes, fewer when one changes nothing. Returns the changes kept; when there
// are any, `segments` is cut to those the last pass checked (the segments after them were
// designed for a path the changes moved: the caller designs them again).
int RefineSegments(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, int passes, std::vector<Values>* segments);

// With targets, `d` a greedy design up to them (DesignSegments with until_targets):
// greedy designs up to them under the other criteria too (each no more than two segments
// longer), the soonest refined (RefineSegments, o.refine_passes passes; one designed slower
// than the soonest so far is not); `d` becomes the one that
// reaches the targets soonest, at the end of its segments, to be designed on from there.
// (Which criterion's greedy choices lead soonest to the targets differs from robot to
// robot: on the reference case D-optimal's, by 15 %.)
void DesignSoonest(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, Design* d);

}  // namespace kincal::plan_internal
