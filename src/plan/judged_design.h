// Designing on for the robots within the prior: once the design point has reached its
// targets, the plan's next segments are chosen for the robots at +-k sigma along the
// prior's axes (plan/within_prior.h) that have not reached them yet. The greedy design
// after the targets serves the design point alone, which needs nothing more; a robot far
// from it (a right wheel 45 % larger) can be left short of one target for a long while by
// controls that suit the design point.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "kincal/plan/design_information.h"
#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"
#include "plan/greedy.h"
#include "plan/within_prior.h"

namespace kincal::plan_internal {

// With targets, `d` a design that has reached them at the design point: up to `count`
// segments more, each the candidate of `grid` that keeps every robot within the prior
// inside (TryCandidate, the greedy's rule) and lowers most the sum of the DesignScores of
// the judges not yet at their targets, each judge's information driven along d's controls
// and the candidate held kHorizonSegments beyond its segment. Stops once every judge is at
// the targets, or where no candidate is safe (each segment's stop was checked). Returns the
// number of segments designed; none when d has not reached the targets.
int DesignForJudges(const System& sys, const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                    const PlanOptions& o, const std::vector<Values>& grid,
                    const std::vector<Judge>& judges, int count, Design* d);

}  // namespace kincal::plan_internal
