#include "daemon/messages.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>

namespace kincal::daemon {
namespace {

// JPEG quality of recorded grey frames (frame_encoding: jpeg): high enough that marker
// centres move by less than their noise (a webcam's own MJPG is typically 75-90).
constexpr int kJpegQuality = 95;
// guidance_t.time_to_target_s beyond what the advice predicts (10 minutes).
constexpr double kBeyondS = 1e9;

}  // namespace

Status FillFrameMessage(const Frame& f, FrameEncoding encoding, std::vector<uint8_t>* png,
                        kincal::frame_t* m) {
  Status encoded;
  m->schema_version = 1;
  m->utime = f.utime;
  m->device_utime = f.device_utime;
  m->sequence = f.sequence;
  m->width = f.width;
  m->height = f.height;
  m->stride = f.stride;
  cv::Mat grey;
  if (encoding != FrameEncoding::kRaw && f.format == PixelFormat::kGrey) {
    encoded = ToGrey(f, &grey);
  }
  if (encoding != FrameEncoding::kRaw && f.format == PixelFormat::kGrey && encoded.ok()) {
    if (encoding == FrameEncoding::kPng) {
      cv::imencode(".png", grey, *png);
      m->pixel_format = "PNG";
    } else {
      cv::imencode(".jpg", grey, *png, {cv::IMWRITE_JPEG_QUALITY, kJpegQuality});
      m->pixel_format = "MJPG";
    }
    m->data.assign(png->begin(), png->end());
  } else {
    m->pixel_format = std::string(PixelFormatName(f.format));
    m->data.resize(f.data.size());
    std::memcpy(m->data.data(), f.data.data(), f.data.size());
  }
  m->size = static_cast<int32_t>(m->data.size());
  return encoded;
}

void FillPoseMessage(const PoseSample& p, kincal::pose_t* m) {
  m->schema_version = 1;
  m->utime = p.utime;
  m->source_utime = p.device_utime;
  m->target_id = 0;
  m->x = p.xytheta.x();
  m->y = p.xytheta.y();
  m->theta = p.xytheta.z();
  for (int i = 0; i < kPoseDim * kPoseDim; ++i) {
    m->covariance[i] = p.covariance(i / kPoseDim, i % kPoseDim);
  }
  m->reprojection_rms_px = p.rms_px;
  m->valid = p.valid ? 1 : 0;
}

void FillMarkersMessage(const PoseSample& p, double sigma_px, kincal::markers_t* m) {
  m->schema_version = 1;
  m->utime = p.utime;
  m->frame_sequence = p.sequence;
  m->num_markers = p.num_markers;
  const auto n = static_cast<long>(p.num_markers);
  m->u.assign(p.u.begin(), p.u.begin() + n);
  m->v.assign(p.v.begin(), p.v.begin() + n);
  m->sigma_px.assign(static_cast<size_t>(n), sigma_px);
  m->id.assign(p.id.begin(), p.id.begin() + n);
  m->target_id.assign(static_cast<size_t>(n), 0);
}

void FillHealthCounters(const DaemonCounters& c, kincal::health_t* m) {
#define KINCAL_HEALTH_FIELD(name, meaning) m->name = c.name;
  KINCAL_DAEMON_COUNTERS(KINCAL_HEALTH_FIELD)
#undef KINCAL_HEALTH_FIELD
}

void FillGuidanceMessage(const System& sys, const std::string& model, const Advice& a,
                         const PlanOptions& o, int64_t utime, kincal::guidance_t* m) {
  m->schema_version = 2;
  m->utime = utime;
  m->model = model;
  const int n = sys.num_params();
  m->parameter = a.worst >= 0 ? sys.params()[static_cast<size_t>(a.worst)].name : "";
  m->sigma = a.worst >= 0 ? a.sigma_now[a.worst] : 0.0;
  m->target = a.worst >= 0 && a.worst_ratio > 0.0 ? m->sigma / a.worst_ratio : 0.0;
  m->sigma_after = a.worst >= 0 ? a.sigma_after[a.worst] : 0.0;
  m->motion = a.motion;
  m->duration_s = a.duration_s;
  m->num_controls = sys.num_controls();
  m->control_names.clear();
  for (const auto& c : sys.model().controls()) m->control_names.push_back(c.name);
  m->controls.assign(a.controls.begin(), a.controls.begin() + sys.num_controls());
  m->time_to_target_s = std::isnan(a.time_to_target_s)   ? -1.0
                        : std::isinf(a.time_to_target_s) ? kBeyondS
                                                         : a.time_to_target_s;
  m->num_params = n;
  m->names.clear();
  m->sigmas.assign(static_cast<size_t>(n), 0.0);
  m->targets.assign(static_cast<size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    m->names.push_back(sys.params()[static_cast<size_t>(i)].name);
    m->sigmas[static_cast<size_t>(i)] = a.sigma_now[i];
    if (o.targets.size() == n) m->targets[static_cast<size_t>(i)] = o.targets[i];
  }
  m->num_path = static_cast<int32_t>(a.path.size());
  m->path_x.clear();
  m->path_y.clear();
  for (const Eigen::Vector3d& q : a.path) {
    m->path_x.push_back(q.x());
    m->path_y.push_back(q.y());
  }
}

}  // namespace kincal::daemon
