#include "daemon/drive_link.h"

#include "daemon/guidance.h"

namespace kincal::daemon {

DriveLink::DriveLink(const GuidanceOptions& options, std::unique_ptr<Workspace> view)
    : opt_(options), view_(std::move(view)) {}

void DriveLink::Offer(const Checkpoint& estimate) {
  {
    std::lock_guard lock(mu_);
    if (!rest_utime_ || kept_ || estimate.utime < *rest_utime_) return;
    kept_ = estimate;
  }
  cv_.notify_all();
}

void DriveLink::Expect(int64_t rest_utime) {
  std::lock_guard lock(mu_);
  rest_utime_ = rest_utime;
  kept_.reset();
}

void DriveLink::Cancel() {
  {
    std::lock_guard lock(mu_);
    cancelled_ = true;
  }
  cv_.notify_all();
}

Status DriveLink::NextLeg(const Eigen::Vector3d& pose, double control_rate_hz,
                          std::chrono::milliseconds wait, ControlSignal* leg) {
  std::optional<Checkpoint> estimate;
  {
    std::unique_lock lock(mu_);
    cv_.wait_for(lock, wait, [this] { return cancelled_ || kept_.has_value(); });
    if (!kept_ || cancelled_) {
      ++failed_;
      return Status::Error(cancelled_ ? "guidance.drive: stopped"
                                      : "guidance.drive: no estimate came while the robot rested "
                                        "(is the target in view and the filter running?)");
    }
    estimate = std::move(kept_);
    kept_.reset();
    rest_utime_.reset();
  }
  const Status s = Plan(*estimate, pose, control_rate_hz, leg);
  std::lock_guard lock(mu_);
  ++(s.ok() ? legs_ : failed_);
  return s;
}

// A plan of horizon_s from `pose`, with the estimate's system, values and covariance.
Status DriveLink::Plan(const Checkpoint& estimate, const Eigen::Vector3d& pose,
                       double control_rate_hz, ControlSignal* leg) const {
  GuidancePlanning g;
  if (Status s = GuidancePlanningFrom(opt_, estimate, &g); !s.ok()) {
    return Status::Error("guidance.drive: " + s.message());
  }
  g.options.duration_s = opt_.horizon_s;
  g.options.control_rate_hz = control_rate_hz;
  g.options.start = pose;
  g.options.seed_with_usual = false;  // a leg every few seconds: the greedy design alone
  g.options.refine_passes = 0;
  Motion plan;
  const Status s = PlanMotion(*g.sys, g.params, estimate.covariance, *view_, g.options, &plan);
  if (!s.ok()) return s;
  *leg = std::move(plan.controls);
  return Status{};
}

int64_t DriveLink::legs() const {
  std::lock_guard lock(mu_);
  return legs_;
}

int64_t DriveLink::legs_failed() const {
  std::lock_guard lock(mu_);
  return failed_;
}

std::unique_ptr<DriveLink> MakeDriveLink(const DaemonConfig& c, const VisionSetup& v) {
  if (!c.guidance.drive) return nullptr;
  return std::make_unique<DriveLink>(
      c.guidance, MakeCameraView(v.camera, v.floor, v.layout, v.target_height_m, c.sim.margin_px));
}

}  // namespace kincal::daemon
