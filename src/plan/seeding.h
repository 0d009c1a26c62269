// The greedy design seeded with the usual motions: each driven for a share of the time it
// needs to reach the targets, then designed on greedily. What a motion people know does
// well early (a figure-eight's turns each way) and what the design adds (the changes that
// tell a lag from a delay) are put together, and the plan is never worse than a usual
// motion the planner's own stay-in rule allows.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"
#include "plan/shaping.h"
#include "plan/within_prior.h"

namespace kincal::plan_internal {

// With targets: for each usual motion in `usual` that is continuous (one segment) and
// reaches them at its design point (time T), the design seeded with it for each share of T
// in kSeedShares (DesignFromSeed; shares whose drive takes a robot within the prior out
// are skipped), designed on greedily until the targets are reached. The seeded design
// that reaches them soonest is designed on to the duration (first for the `judges` short
// of them, DesignForJudges); it replaces `plan` (evaluated) when it ranks better
// (MotionRank), named after its seed. Returns whether it did. Without targets, nothing is
// done.
bool SeedWithUsual(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, const std::vector<Motion>& usual,
                   const std::vector<Judge>& judges, Motion* plan);

}  // namespace kincal::plan_internal
