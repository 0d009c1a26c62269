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

vision::FloorPoseSolverOptions SolverOptions(const PoseOptions& pose) {
  vision::FloorPoseSolverOptions o;
  o.method = pose.method == PoseMethod::kGroundPlane ? vision::FloorPoseMethod::kGroundPlane
                                                     : vision::FloorPoseMethod::kLowe;
  o.sigma_px = pose.sigma_px;
  o.max_rms_px = pose.max_rms_px;
  return o;
}

}  // namespace

PoseStage::PoseStage(const PoseOptions& pose, const vision::DetectorOptions& detector,
                     const VisionSetup& v)
    : opt_(pose),
      vis_(v),
      tracker_(v.camera, v.layout, detector),
      solver_(v.camera, v.floor, v.layout, v.target_height_m, SolverOptions(pose)),
      centre_variance_(pose.sigma_px * pose.sigma_px) {}

bool PoseStage::Process(const Frame& f, PoseSample* p, std::string* error) {
  *p = PoseSample{};
  p->utime = f.utime;
  p->device_utime = f.device_utime;
  p->sequence = f.sequence;
  p->arrival_mono_ns = f.arrival_mono_ns;
  if (const Status s = ToGrey(f, &grey_); !s.ok()) {
    *error = s.message();
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
  vision::PlanarPose r;
  if (!solver_.Solve(markers, have_last_ ? &last_pose_ : nullptr, &r)) return;
  p->xytheta = r.xytheta;
  p->covariance = r.covariance;
  p->rms_px = r.rms_px;
  p->xytheta.z() = WrapAngle(p->xytheta.z());
  p->valid = true;
  last_pose_ = p->xytheta;
  have_last_ = true;
  CalibrateCovariance(static_cast<int>(markers.size()), p);
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
