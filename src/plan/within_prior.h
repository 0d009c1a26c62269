// How the plan does for robots other than the design point: driven by the robots at
// +-prior_sigmas along each axis of the prior, against the quickest usual motion at each.
// The plan is designed at the design point, then for these robots once the design point
// is at its targets (plan/judged_design.h); where the true robot is far from it, its lead
// over the usual motions can still shrink (on the tests' reference case, from 1.69x at the
// design point to 1.18x where the delay is 0.3 s below the guess), and the user is told
// where.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"

namespace kincal::plan_internal {

// A robot the plan is judged at: a name ("r_l -3 sigma"), its parameters and the time
// the quickest usual motion needs to reach the targets there.
struct Judge {
  std::string name;
  Eigen::VectorXd params;
  double usual_s = 0.0;
};

// With targets: the design point and the robots at +-o.prior_sigmas along each principal
// axis of the prior that are within every parameter's physical bound (a lag of -0.2 s is
// no robot), each named; held parameters' axes move no robot and are skipped. usual_s is
// left 0 (JudgesWithinPrior times them). Empty without targets.
std::vector<Judge> RobotsToJudge(const System& sys, const Eigen::VectorXd& params,
                                 const Eigen::MatrixXd& prior_cov, const PlanOptions& o);

// `robots` (RobotsToJudge), each with the time the quickest motion of `usual` needs there
// (the continuous ones every robot within the prior survives; a stopped one driven on);
// robots no such motion brings to the targets within the duration are left out.
std::vector<Judge> JudgesWithinPrior(const System& sys, const std::vector<Judge>& robots,
                                     const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                     const PlanOptions& o, const std::vector<Motion>& usual);

// `plan` driven by each judge: its within_prior (the usual motion's time and the plan's
// there, infinity when it does not reach the targets within the duration).
void JudgePlan(const System& sys, const Eigen::MatrixXd& prior_cov, const Workspace& ws,
               const PlanOptions& o, const std::vector<Judge>& judges, Motion* plan);

}  // namespace kincal::plan_internal
