#include "daemon/detection_stage.h"

#include <kincal/markers_t.hpp>
#include <kincal/pose_t.hpp>

#include "daemon/messages.h"
#include "daemon/sources.h"

namespace kincal::daemon {

DetectionStage::DetectionStage(PoseStage* stage, DetectionOptions options, Publisher* publisher,
                               BoundedQueue<Frame>* in, BoundedQueue<PoseSample>* out,
                               CounterSet* counters, PreviewStage* preview)
    : stage_(*stage),
      opt_(std::move(options)),
      publisher_(*publisher),
      in_(*in),
      out_(*out),
      counters_(*counters),
      preview_(preview) {}

void DetectionStage::Run() {
  Frame f;
  PoseSample p;
  kincal::pose_t pose_msg{};
  kincal::markers_t markers_msg{};
  std::string error;
  while (true) {
    if (!in_.Pop(f, std::chrono::milliseconds(100))) {
      if (in_.closed_and_empty()) break;
      continue;
    }
    if (!stage_.Process(f, &p, &error)) {
      counters_.frames_bad.fetch_add(1);
      std::lock_guard lock(mu_);
      last_frame_error_ = error;
      continue;
    }
    (p.valid ? counters_.poses_valid : counters_.poses_invalid).fetch_add(1);
    {
      std::lock_guard lock(mu_);
      if (last_target_utime_ < 0 || p.valid) last_target_utime_ = p.utime;
      last_frame_utime_ = p.utime;
    }
    // Publish the pose (and markers) now: this is the frame-to-publish latency.
    FillPoseMessage(p, &pose_msg);
    publisher_.Publish(opt_.pose_channel, p.utime, pose_msg);
    counters_.poses_published.fetch_add(1);
    if (opt_.publish_markers) {
      FillMarkersMessage(p, opt_.marker_sigma_px, &markers_msg);
      publisher_.Publish(opt_.markers_channel, p.utime, markers_msg);
    }
    if (p.arrival_mono_ns > 0) {
      const double ms = NsToSeconds(MonotonicNs() - p.arrival_mono_ns) * 1e3;
      std::lock_guard lock(mu_);
      latency_total_.Add(ms);
      latency_window_.Add(ms);
    }
    const int64_t utime = p.utime;
    const bool has_pose = p.valid;
    const Eigen::Vector3d pose = p.xytheta;
    out_.Push(p);  // swaps: p holds a recycled sample from here on
    if (preview_ != nullptr)
      preview_->Offer(stage_.grey(), utime, f.sequence, has_pose ? &pose : nullptr);
  }
  out_.Close();
}

DetectionStage::Status DetectionStage::TakeStatus(bool reset_window) {
  std::lock_guard lock(mu_);
  Status s;
  s.last_frame_error = last_frame_error_;
  s.window_p50_ms = latency_window_.Percentile(0.5);
  s.window_p99_ms = latency_window_.Percentile(0.99);
  s.total_p50_ms = latency_total_.Percentile(0.5);
  s.total_p99_ms = latency_total_.Percentile(0.99);
  s.total_max_ms = latency_total_.max_ms();
  if (last_frame_utime_ >= 0)
    s.seconds_without_target = 1e-6 * (last_frame_utime_ - last_target_utime_);
  if (reset_window) latency_window_.Reset();
  return s;
}

}  // namespace kincal::daemon
