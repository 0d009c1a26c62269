// The robots a plan must keep inside the workspace (the prior's fleet), driven along its
// controls: the planner's stay-in rule and EveryRobotStaysIn's, and what they share.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"

namespace kincal::plan_internal {

inline constexpr double kFleetCheckS = 0.05;  // how often the fleet is checked (s)

// Robot states driven along the plan, for the stay-in check: the design point, then the
// robots at + and - k sigma along each principal axis of the prior, in pairs.
struct Fleet {
  std::vector<StateVec> x;
  double t_s = 0.0;
};

// The robots that must stay in: the design point, then +-k sigma along each principal
// axis of the prior, in pairs (the axis order of Eigen's SelfAdjointEigenSolver).
std::vector<Eigen::VectorXd> RobotsWithinPrior(const Eigen::VectorXd& params,
                                               const Eigen::MatrixXd& prior_cov, double k);

// Whether the fleet's targets are inside: FleetInside, the planner's rule (the axis robots
// and the prior ellipsoid's poses between them, pushed a fifth further out), or
// CornersInside (the design point and the axis robots only).
bool FleetInside(const System& sys, const Workspace& ws, const Fleet& f);
bool CornersInside(const System& sys, const Workspace& ws, const Fleet& f);
using FleetCheck = bool (*)(const System&, const Workspace&, const Fleet&);

// Drives the fleet to t1, checking every `check_s` with `inside_check`; false if any
// target left (with `stop_early`, as soon as one does, leaving the fleet there).
bool DriveFleet(const System& sys, const ControlSignal& u, const Workspace& ws, double t1,
                double check_s, bool stop_early, Fleet* f, FleetCheck inside_check = FleetInside);

// The fleet at the start pose, at rest: the design point and the robots at
// +-o.prior_sigmas along each principal axis of the prior.
Fleet FleetAtStart(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Eigen::Vector3d& start,
                   const PlanOptions& o, const ControlSignal& u);

// The fleet from the start pose (StartPose) through the whole of `u`, to its last sample,
// checked every kFleetCheckS with `inside_check` (FleetInside: the planner's own rule;
// CornersInside: EveryRobotStaysIn's).
bool FleetStaysInside(const System& sys, const Eigen::VectorXd& params,
                      const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                      const ControlSignal& u, FleetCheck inside_check = FleetInside);

}  // namespace kincal::plan_internal
