// What `kincal plan` writes and says: the plan as controls CSV (the format `kincal
// analyze --controls` reads), the predicted sigma of every motion as JSON, a summary, and
// the plan played as kincal.controls_t on LCM.
#pragma once

#include <Eigen/Core>
#include <ostream>
#include <string>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/status.h"
#include "kincal/system.h"

namespace kincal {

// DIR/plan.csv and DIR/plan.json, each written atomically (DIR is created).
Status WritePlanFiles(const std::string& dir, const System& sys, const Eigen::VectorXd& params,
                      const Eigen::MatrixXd& prior_cov, const PlanOptions& o, const Motion& plan,
                      const std::vector<Motion>& usual);

// Controls CSV: "t,<control names>" then one row per sample, t in seconds.
std::string ControlsCsv(const System& sys, const ControlSignal& u);

// The table a user reads: final sigma per parameter and time to the targets, per motion.
void PrintPlanSummary(const System& sys, const PlanOptions& o, const Motion& plan,
                      const std::vector<Motion>& usual, std::ostream& out);

// Plays the plan in real time as kincal.controls_t on `channel` (LCM's default URL or
// $LCM_DEFAULT_URL), utime the host's realtime clock; an error names LCM's failure.
Status PublishPlan(const System& sys, const Motion& plan, const std::string& channel);

}  // namespace kincal
