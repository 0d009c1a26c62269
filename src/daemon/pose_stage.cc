// Detection and pose of one frame.
#include "daemon/pose_stage.h"

#include "kincal/angles.h"
#include "kincal/vision/pose.h"

namespace kincal::daemon {
namespace {

// The centre noise is a running mean over this many frames ...
constexpr int kCentreNoiseFrames = 200;
// ... and never taken below (0.002 px)^2 (a perfect synthetic image).
constexpr double kMinCentreVariance = 4e-6;

}  // namespace

PoseStage::PoseStage(const PoseOptions& pose, const vision::DetectorOptions& detector,
                     const VisionSetup& v)
    : opt_(pose),
      vis_(v),
      tracker_(v.camera, v.layout, detector),
      centre_variance_(pose.sigma_px * pose.sigma_px) {}

bool PoseStage::Process(const Frame& f, PoseSample* p, std::string* error) {
  *p = PoseSample{};
  p->utime = f.utime;
  p->device_utime = f.device_utime;
  p->sequence = f.sequence;
  p->arrival_mono_ns = f.arrival_mono_ns;
  try {
    ToGrey(f, &grey_);
  } catch (const FrameError& e) {
    *error = e.what();
    return false;
  }
  if (grey_.cols != vis_.camera.width || grey_.rows != vis_.camera.height) {
    *error = "frame is " + std::to_string(grey_.cols) + "x" + std::to_string(grey_.rows) +
             " but the camera intrinsics are for " + std::to_string(vis_.camera.width) + "x" +
             std::to_string(vis_.camera.height);
    return false;
  }
  auto markers = tracker_.Track(grey_);
  p->num_markers = std::min<int>(static_cast<int>(markers.size()), kMaxMarkers);
  for (int i = 0; i < p->num_markers; ++i) {
    const auto& m = markers[static_cast<size_t>(i)];
    p->u[static_cast<size_t>(i)] = m.centre_px.x();
    p->v[static_cast<size_t>(i)] = m.centre_px.y();
    p->id[static_cast<size_t>(i)] = m.id;
  }
  if (markers.size() == vis_.layout.markers.size() &&
      markers.size() <= static_cast<size_t>(kMaxMarkers)) {
    Solve(markers, p);
    // The centre of a marker's image is not the image of its centre: correct by the
    // current pose and solve once more.
    if (p->valid) {
      vision::CorrectPerspectiveBias(
          vis_.camera, vision::CameraPoseOnFloor(vis_.floor, p->xytheta, vis_.target_height_m),
          vis_.layout, &markers);
      Solve(markers, p);
    }
  }
  if (!p->valid) have_last_ = false;
  return true;
}

void PoseStage::Solve(const std::vector<vision::Marker>& markers, PoseSample* p) {
  p->valid = false;
  const int nm = static_cast<int>(markers.size());
  for (int i = 0; i < nm; ++i) {
    const auto& m = markers[static_cast<size_t>(i)];
    if (m.id < 0) return;
    const auto& q = vis_.layout.markers[static_cast<size_t>(m.id)];
    obj_[static_cast<size_t>(i)] = Eigen::Vector3d(q.x(), q.y(), 0.0);
    norm_[static_cast<size_t>(i)] = vis_.camera.PixelToNormalized(m.centre_px);
  }
  const std::span<const Eigen::Vector3d> o(obj_.data(), static_cast<size_t>(nm));
  const std::span<const Eigen::Vector2d> n(norm_.data(), static_cast<size_t>(nm));
  Eigen::Vector3d init = last_pose_;
  vision::Pose3 pose3;
  if (!have_last_ || opt_.method == PoseMethod::kLowe) {
    if (!vision::PlanarInitialPose(o, n, &pose3)) return;
    init = vision::FloorPoseOf(vis_.floor, pose3);
  }
  if (opt_.method == PoseMethod::kGroundPlane) {
    const auto r = vision::GroundPlanePose(vis_.floor, vis_.target_height_m, o, n, init,
                                           vis_.camera.fx, opt_.sigma_px);
    if (!r.ok || !(r.rms_px <= opt_.max_rms_px) || !r.xytheta.allFinite()) return;
    p->xytheta = r.xytheta;
    p->covariance = r.covariance;
    p->rms_px = r.rms_px;
  } else {
    const auto lowe = vision::LevelLowePose(vis_.floor, o, n, pose3, vis_.camera.fx, opt_.sigma_px);
    if (!lowe.ok || !(lowe.rms_px <= opt_.max_rms_px)) return;
    const vision::PlanarPose r =
        vision::FloorPoseFromLoweAtHeight(vis_.floor, lowe, vis_.target_height_m);
    if (!r.ok) return;
    p->xytheta = r.xytheta;
    p->covariance = r.covariance;
    p->rms_px = r.rms_px;
  }
  p->xytheta.z() = WrapAngle(p->xytheta.z());
  p->valid = true;
  last_pose_ = p->xytheta;
  have_last_ = true;
  CalibrateCovariance(nm, p);
}

// The residual variance of a solve, RSS / (residuals - unknowns), is an unbiased sample
// of the centre noise; its running mean replaces the configured sigma_px, so that the
// covariance the filter weighs the pose with matches the scatter of the poses.
void PoseStage::CalibrateCovariance(int num_markers, PoseSample* p) {
  const int residuals = 2 * num_markers;
  const int unknowns = opt_.method == PoseMethod::kGroundPlane ? 3 : 6;
  if (residuals > unknowns) {
    const double sample = p->rms_px * p->rms_px * residuals / (residuals - unknowns);
    const double w = 1.0 / std::min(++centre_samples_, kCentreNoiseFrames);
    centre_variance_ += w * (sample - centre_variance_);
  }
  const double configured = opt_.sigma_px * opt_.sigma_px;
  p->covariance *= std::max(centre_variance_, kMinCentreVariance) / configured;
}

}  // namespace kincal::daemon
