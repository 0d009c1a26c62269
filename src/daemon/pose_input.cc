#include "daemon/pose_input.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <kincal/pose_t.hpp>

#include "daemon/messages.h"

namespace kincal::daemon {
namespace {

bool PositiveDefinite(const Eigen::Matrix3d& c) {
  if (!c.allFinite() || !c.isApprox(c.transpose(), 1e-9)) return false;
  const Eigen::LLT<Eigen::Matrix3d> llt(c);
  return llt.info() == Eigen::Success;
}

}  // namespace

bool DecodeLoggedPose(const void* data, size_t n, int64_t utime_shift,
                      const std::array<double, 3>& sigma, PoseSample* out, std::string* why) {
  kincal::pose_t m;
  if (m.decode(data, 0, static_cast<int>(n)) < 0) {
    *why = "not a kincal.pose_t (" + std::to_string(n) + " bytes)";
    return false;
  }
  if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.theta)) {
    *why = "a pose_t at utime " + std::to_string(m.utime) + " with a value that is not finite";
    return false;
  }
  *out = PoseSample{};
  out->utime = m.utime + utime_shift;
  out->device_utime = m.source_utime != 0 ? m.source_utime + utime_shift : 0;
  out->valid = m.valid != 0;
  out->xytheta = Eigen::Vector3d(m.x, m.y, m.theta);
  for (int i = 0; i < 9; ++i) out->covariance(i / 3, i % 3) = m.covariance[i];
  if (!PositiveDefinite(out->covariance)) {
    out->covariance = Eigen::Vector3d(sigma[0], sigma[1], sigma[2]).cwiseAbs2().asDiagonal();
  }
  out->rms_px = std::isfinite(m.reprojection_rms_px) ? m.reprojection_rms_px : 0.0;
  return true;
}

void PoseReceiver::OnMessage(const void* data, size_t n, int64_t utime_shift) {
  PoseSample p;
  thread_local std::string why;
  if (!DecodeLoggedPose(data, n, utime_shift, sigma_, &p, &why)) {
    if (counters_.frames_bad.fetch_add(1) == 0) spdlog::warn("replay: rejected a pose: {}", why);
    std::lock_guard lock(mu_);
    last_reject_ = why;
    return;
  }
  (p.valid ? counters_.poses_valid : counters_.poses_invalid).fetch_add(1);
  kincal::pose_t msg{};
  FillPoseMessage(p, &msg);
  publisher_.Publish(channel_, p.utime, msg);
  counters_.poses_published.fetch_add(1);
  out_.Push(p);
}

std::string PoseReceiver::last_reject() const {
  std::lock_guard lock(mu_);
  return last_reject_;
}

}  // namespace kincal::daemon
