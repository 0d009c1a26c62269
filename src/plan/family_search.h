// The best of a family of usual motions (a square, a circle each way, a figure-eight): its
// sizes and speeds searched, and each motion judged as the plan is, whole or stopped once
// it has reached the targets.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"

namespace kincal::plan_internal {

// A member of a family: the motion of a size (m: a side, a radius) driven at a fraction of
// the fastest that size allows within the limits; nothing when the limits or the time
// allow none.
using FamilyMember = std::function<std::optional<Motion>(double size, double speed)>;

// The sizes tried: `count` from `smallest` to `largest`, evenly in ratio.
struct FamilySizes {
  double smallest = 0.0, largest = 0.0;
  int count = 1;
};

// n sizes from lo to hi, evenly in ratio (hi alone when lo is not below it).
std::vector<double> SizesBetween(double lo, double hi, int n);

// Every size at speeds 0.4, 0.6, 0.8 and 1.0, then about the best that stays in at the
// design point: half a step of sizes each way and a tenth of the fastest speed each way.
// Returned: the best (MotionRank) that keeps every robot within the prior inside
// (EveryRobotStaysIn), whole or stopped once it reaches the targets (StoppedAtTargets);
// before it, when better, the best at the design point only (every_robot_stays_in
// false). When none stays in even at the design point, the best of all; nothing when the
// family has no member.
std::vector<Motion> BestOfFamily(const FamilyMember& member, const FamilySizes& sizes,
                                 const System& sys, const Eigen::VectorXd& params,
                                 const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                 const PlanOptions& o);

// `m` (evaluated) driven until it reaches the targets, then stopped at the acceleration
// limits (`unstopped` keeps the whole), evaluated: the motion as someone drives it who
// stops once it has done its work, which the prior's robots may survive where the whole
// of `m` takes one out. Nothing when `m` does not reach the targets, or reaches them too
// late to stop before the duration.
std::optional<Motion> StoppedAtTargets(const System& sys, const Eigen::VectorXd& params,
                                       const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                       const PlanOptions& o, const Motion& m);

}  // namespace kincal::plan_internal
