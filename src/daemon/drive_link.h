// guidance.drive: the simulated robot drives what the planner makes of the running
// estimate. It drives in legs: a plan of guidance.horizon_s from where it stands (kincal
// plan's greedy design, the camera's view as workspace, kept in view for every robot
// within the estimate's 3 sigma), a stop at the acceleration limits, then
// guidance.drive_pause_s at rest. The next leg is planned from the first estimate the
// filter publishes after the pause began: the robot has not moved since, so the plan
// starts where the estimate is, and a lossless run is the same every time.
//
// The filter thread offers every estimate and never waits; the simulated camera's thread
// waits for the estimate its next leg needs (at most kDriveWait) and plans it.
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>

#include "daemon/sources.h"
#include "kincal/control_signal.h"
#include "kincal/daemon/config.h"
#include "kincal/io/checkpoint.h"
#include "kincal/plan/workspace.h"
#include "kincal/status.h"

namespace kincal::daemon {

// How long the simulated robot waits for the estimate of its next leg (wall clock).
inline constexpr std::chrono::seconds kDriveWait{20};

class DriveLink {
 public:
  // `options` must be valid for the configured robot (DaemonConfig::IsValid); `view`: where
  // the target must stay.
  DriveLink(const GuidanceOptions& options, std::unique_ptr<Workspace> view);

  // Filter thread: every published estimate (copied only when it is the one a leg waits for).
  void Offer(const Checkpoint& estimate);
  // Simulated camera's thread: the robot stops and rests from `rest_utime` on (pipeline
  // time, us); its next leg will be planned from the first estimate at or after it.
  void Expect(int64_t rest_utime);
  // Simulated camera's thread: the next leg, from robot pose (x, y, theta) at rest: its
  // controls from 0 (at control_rate_hz, ending at rest). Waits for the estimate Expect
  // named (at most `wait`). An error when it did not come (timed out, cancelled) or the
  // planner found no leg that keeps every robot within the estimate in view.
  Status NextLeg(const Eigen::Vector3d& pose, double control_rate_hz,
                 std::chrono::milliseconds wait, ControlSignal* leg);
  // Wakes a waiting NextLeg (shutdown); later ones fail at once.
  void Cancel();

  int64_t legs() const;         // legs planned
  int64_t legs_failed() const;  // legs that could not be planned

 private:
  Status Plan(const Checkpoint& estimate, const Eigen::Vector3d& pose, double control_rate_hz,
              ControlSignal* leg) const;

  const GuidanceOptions opt_;
  const std::unique_ptr<Workspace> view_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::optional<int64_t> rest_utime_;  // the leg expected
  std::optional<Checkpoint> kept_;     // its estimate, once offered
  bool cancelled_ = false;
  int64_t legs_ = 0, failed_ = 0;
};

// kincald's link (null unless guidance.drive): legs planned inside the view of the camera
// and floor calibration in `v`, sim.margin_px from the image edge.
std::unique_ptr<DriveLink> MakeDriveLink(const DaemonConfig& c, const VisionSetup& v);

}  // namespace kincal::daemon
