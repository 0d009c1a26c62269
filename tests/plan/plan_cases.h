// The robots the plan layer's unit tests share: a unicycle with a lag (fast to plan for),
// issue 34's reference robot (a differential drive with a lag, a delay and a lever arm)
// and issue 34's own command for it, each with its prior, limits, targets and a 3 x 2 m
// arena.
#pragma once

#include <Eigen/Core>
#include <memory>

#include "kincal/plan/planner.h"
#include "kincal/plan/workspace.h"

namespace kincal::plan_testing {

struct UnicycleWithALag {
  System sys = MakeSystem("unicycle", {"actuator_lag"}).value();
  Eigen::Vector3d p{1.0, 1.0, 0.15};
  Eigen::Matrix3d prior = Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal();
  PlanOptions o;
  std::unique_ptr<Workspace> ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  explicit UnicycleWithALag(double duration_s) {
    o.duration_s = duration_s;
    o.max_abs = {0.5, 2.0};
    o.max_accel = {1.0, 4.0};
    o.targets = Eigen::Vector3d(1e-3, 1e-3, 3e-3);
  }
};

struct ReferenceRobot {
  System sys = MakeSystem("diffdrive", {"actuator_lag", "time_offset", "lever_arm"}).value();
  Eigen::VectorXd p = (Eigen::VectorXd(8) << 0.03, 0.03, 0.3, 0.1, 0.0, 0.0, 0.0, 0.0).finished();
  Eigen::MatrixXd prior = (Eigen::VectorXd(8) << 0.003, 0.003, 0.03, 0.1, 0.1, 0.05, 0.05, 0.05)
                              .finished()
                              .cwiseAbs2()
                              .asDiagonal();
  PlanOptions o;
  std::unique_ptr<Workspace> ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  explicit ReferenceRobot(double duration_s) {
    o.duration_s = duration_s;
    o.max_abs = {20.0, 20.0};
    o.max_accel = {40.0, 40.0};
    o.targets = (Eigen::VectorXd(8) << 3e-5, 3e-5, 3e-4, 3e-3, 3e-3, 2e-3, 2e-3, 0.0).finished();
    o.care = {0, 1, 2, 3, 4, 5, 6};
  }
};

// Issue 34's own command: `kincal plan --model diffdrive --effects
// actuator_lag,time_offset,lever_arm --init r_l=0.033,r_r=0.033,d=0.3,tau_s=0.1
// --arena=-1.5,-1,1.5,1 --duration 60 --limits omega_l=15,omega_r=15,accel=20 --targets
// (0.1 % of the guess, 3 ms, 2 mm)`, with the generic prior (the radii to 0.005 m), for a
// true robot whose radii are 0.03 m (10 % off the guess).
struct Issue34Command : ReferenceRobot {
  Issue34Command() : ReferenceRobot(60.0) {
    p[0] = p[1] = 0.033;
    prior(0, 0) = prior(1, 1) = 0.005 * 0.005;
    o.max_abs = {15.0, 15.0};
    o.max_accel = {20.0, 20.0};
    o.targets[0] = o.targets[1] = 3.3e-5;
  }
};

}  // namespace kincal::plan_testing
