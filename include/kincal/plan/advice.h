// What to drive next: from the current estimate and its covariance (a kincald checkpoint,
// an analyze report), which parameter is furthest from its target sigma, which motion held
// for a few seconds would determine it best, and the predicted driving time until every
// target is met. The heart of online guidance, usable offline (`kincal plan --advise`).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/plan/planner.h"
#include "kincal/status.h"
#include "kincal/system.h"

namespace kincal {

struct Advice {
  int worst = -1;                    // the scored parameter with the largest sigma / target
  double worst_ratio = 0.0;          // its sigma over its target (or its prior sigma)
  ControlSignal::Values controls{};  // the motion to drive, held for duration_s
  double duration_s = 0.0;
  Eigen::Vector2d twist = Eigen::Vector2d::Zero();  // (v m/s, omega rad/s) at the estimate
  std::string motion;                               // "turn left at 0.50 rad/s for 3 s"
  Eigen::VectorXd sigma_now, sigma_after;           // of every parameter
  // Predicted driving time to every target along a greedy plan from the estimate (in an
  // open floor): NaN without targets, +inf when 10 minutes are not enough.
  double time_to_target_s = 0.0;
  // Where the motion takes the target: its measured pose (x, y, theta) every kPathStepS
  // from the start to duration_s, in the frame of the target where it starts (x ahead, y
  // to its left), slewing as the limits allow, at the estimate.
  std::vector<Eigen::Vector3d> path;
  static constexpr double kPathStepS = 0.1;
};

// `o` supplies limits, targets, scored parameters and pose noise; `horizon_s` is how long
// the advised motion is held. Errors (options that do not fit the system) are statuses.
Status Advise(const System& sys, const Eigen::VectorXd& params, const Eigen::MatrixXd& cov,
              const PlanOptions& o, double horizon_s, Advice* out);

// Words for a twist held for `seconds`: "drive forward at 0.30 m/s", "turn in place left at
// 1.2 rad/s", "drive forward at 0.30 m/s turning right at 0.50 rad/s (radius 0.60 m)".
std::string DescribeMotion(const Eigen::Vector2d& twist, double seconds);

}  // namespace kincal
