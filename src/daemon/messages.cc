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

void FillFrameMessage(const Frame& f, FrameEncoding encoding, std::vector<uint8_t>* png,
                      kincal::frame_t* m) {
  m->schema_version = 1;
  m->utime = f.utime;
  m->device_utime = f.device_utime;
  m->sequence = f.sequence;
  m->width = f.width;
  m->height = f.height;
  m->stride = f.stride;
  if (encoding != FrameEncoding::kRaw && f.format == PixelFormat::kGrey) {
    cv::Mat grey;
    ToGrey(f, &grey);
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

void FillParamsMessage(const System& sys, const StateVec& state, const StateMat& covariance,
                       std::string_view estimator, int64_t update_count, int64_t utime,
                       kincal::params_t* m) {
  const size_t n = static_cast<size_t>(sys.num_params());
  m->schema_version = 3;
  m->utime = utime;
  m->model = std::string(sys.model().name());
  m->estimator = std::string(estimator);
  m->num_params = static_cast<int32_t>(n);
  m->names.resize(n);
  m->units.resize(n);
  m->values.resize(n);
  m->sigmas.resize(n);
  m->covariance.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const int a = static_cast<int>(i);
    m->names[i] = sys.params()[i].name;
    m->units[i] = sys.params()[i].unit;
    m->values[i] = state[a];
    m->sigmas[i] = std::sqrt(std::max(0.0, covariance(a, a)));
    m->covariance[i].resize(n);
    for (size_t k = 0; k < n; ++k) m->covariance[i][k] = covariance(a, static_cast<int>(k));
  }
  m->update_count = update_count;
  m->source = kincal::params_t::SOURCE_FILTER;
}

namespace {

// names, units, values, sigmas and the covariance of a batch calibration into the vectors
// of a params_t or a calibration_t (the two lay them out alike).
template <typename Message>
void FillParameterBlock(const BatchCalibration& c, Message* m) {
  const size_t n = c.params.size();
  m->num_params = static_cast<int32_t>(n);
  m->names.resize(n);
  m->units.resize(n);
  m->values.resize(n);
  m->sigmas.resize(n);
  m->covariance.resize(n);
  for (size_t i = 0; i < n; ++i) {
    m->names[i] = c.params[i].name;
    m->units[i] = c.params[i].unit;
    m->values[i] = c.params[i].value;
    m->sigmas[i] = c.params[i].sigma;
    m->covariance[i].resize(n);
    for (size_t k = 0; k < n; ++k) {
      m->covariance[i][k] = c.covariance(static_cast<int>(i), static_cast<int>(k));
    }
  }
}

}  // namespace

void FillParamsFromCalibration(const BatchCalibration& c, const std::string& model,
                               int64_t update_count, int64_t utime, kincal::params_t* m) {
  m->schema_version = 3;
  m->utime = utime;
  m->model = model;
  m->estimator = "batch";
  FillParameterBlock(c, m);
  m->update_count = update_count;
  m->source = kincal::params_t::SOURCE_BATCH;
}

void FillCalibrationMessage(const BatchCalibration& run, const BatchCalibration* good,
                            const std::string& model, int64_t poses_thinned,
                            kincal::calibration_t* m) {
  m->schema_version = 1;
  m->utime = PipelineNsToUtime(run.data_end_ns);
  m->sequence = run.sequence;
  m->ok = run.ok ? 1 : 0;
  m->error = run.error;
  m->data_begin_utime = PipelineNsToUtime(run.data_begin_ns);
  m->data_end_utime = PipelineNsToUtime(run.data_end_ns);
  m->num_poses = run.num_poses;
  m->num_controls = run.num_controls;
  m->poses_thinned = poses_thinned;
  m->compute_s = run.compute_s;
  const BatchCalibration none;
  const BatchCalibration& c = good != nullptr ? *good : none;
  m->calibration_sequence = good != nullptr ? good->sequence : 0;
  m->model = ModelLabel(model, c.effects);
  m->num_effects = static_cast<int32_t>(c.effects.size());
  m->effects = c.effects;
  FillParameterBlock(c, m);
  m->num_accepted = static_cast<int32_t>(c.accepted.size());
  m->accepted = c.accepted;
  m->accepted_evidence = c.accepted_evidence;
  m->accepted_evidence.resize(c.accepted.size());
  m->horizon_s = c.horizon_s;
  m->heldout_before_m = c.heldout_before_m;
  m->heldout_after_m = c.heldout_after_m;
  m->heldout_before_rad = c.heldout_before_rad;
  m->heldout_after_rad = c.heldout_after_rad;
  m->unique = c.unique ? 1 : 0;
  m->warnings = c.warnings;
  m->prior = c.prior;
}

kincal::model_check_t ModelCheckMessage(const ModelCheckVerdict& v, const std::string& model,
                                        int64_t utime) {
  kincal::model_check_t m{};
  m.schema_version = 2;
  m.utime = utime;
  m.model = model;
  m.consistent = v.consistent ? 1 : 0;
  m.nis_mean = v.nis_mean;
  m.nis_expected = v.nis_expected;
  m.window = v.window;
  m.window_capacity = v.window_capacity;
  m.suspected_effect = v.suspected_effect;
  m.num_candidates = static_cast<int32_t>(v.candidates.size());
  m.candidates = v.candidates;
  m.confidence = v.confidence;
  m.evidence = v.evidence;
  m.num_added = 0;
  return m;
}

void FillHealthCounters(const DaemonCounters& c, kincal::health_t* m) {
#define KINCAL_HEALTH_FIELD(name, meaning) m->name = c.name;
  KINCAL_DAEMON_COUNTERS(KINCAL_HEALTH_FIELD)
#undef KINCAL_HEALTH_FIELD
}

std::string ModelLabel(std::string_view model, const std::vector<std::string>& effects) {
  std::string label(model);
  for (const auto& e : effects) label += "+" + e;
  return label;
}

void FillGuidanceMessage(const System& sys, const std::string& model, const Advice& a,
                         const PlanOptions& o, int64_t utime, kincal::guidance_t* m) {
  m->schema_version = 1;
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
}

}  // namespace kincal::daemon
