// Replay of a kincald LCM log: frames go through the pipeline again, controls to the
// filter with their recorded receive times. A log without frames (motion capture imported
// by `kincal import`) is replayed from its logged poses instead.
#include <spdlog/spdlog.h>

#include <atomic>
#include <cstring>
#include <kincal/frame_t.hpp>
#include <optional>
#include <thread>

#include "daemon/sources.h"
#include "kincal/io/lcm_guard.h"
#include "kincal/io/lcm_log_reader.h"

namespace kincal::daemon {
namespace {

class ReplaySource final : public FrameSource {
 public:
  ReplaySource(const ReplayOptions& replay, const LcmOptions& lcm, ControlIntake controls,
               PoseIntake poses)
      : opt_(replay), lcm_(lcm), intake_(std::move(controls)), pose_intake_(std::move(poses)) {}
  ~ReplaySource() override {
    if (log_) ReportDamage();
  }
  std::string name() const override { return "replay(" + opt_.path + ")"; }
  Status Start() override {
    if (!log_) {
      if (const Status s = LcmLogReader::Open(opt_.path, &log_); !s.ok()) {
        return Status::Error("replay: " + s.message());
      }
      if (log_->size() == 0) {
        log_.reset();
        return Status::Error("replay: " + opt_.path +
                             ": the log is empty (0 bytes), nothing to replay");
      }
      if (Status s = ChooseMeasurements(); !s.ok()) {
        log_.reset();
        return s;
      }
    }
    start_mono_ = MonotonicNs();
    return {};
  }
  void Stop() override { stopped_ = true; }
  SourceCapabilities capabilities() const override {
    return {.lossless = opt_.speed <= 0,
            .carries_controls = true,
            .controls_end_with_frames = true,
            .can_reopen = false};
  }

  SourceStatus Next(Frame* f, int /*timeout_ms*/, std::string* error) override {
    while (!stopped_) {
      const bool got = log_->Next(&ev_);
      damaged_.store(log_->damaged_stretches(), std::memory_order_relaxed);
      if (!got) {
        ReportDamage();
        // End of the log: again, shifted later by its span plus one nominal frame period,
        // so that time keeps increasing.
        if (++loop_ >= opt_.loops || last_utime_ == INT64_MIN) return SourceStatus::kEnd;
        offset_ += last_utime_ - first_utime_ + 33'333;
        log_->Rewind();
        continue;
      }
      const LcmLogEvent* ev = &ev_;
      ++events_;
      if (first_utime_ == INT64_MIN) first_utime_ = ev->timestamp;
      if (loop_ == 0) last_utime_ = std::max(last_utime_, ev->timestamp);
      if (opt_.speed > 0) Pace(ev->timestamp + offset_);
      const std::string_view channel(ev->channel);
      if (channel == lcm_.controls_channel) {
        intake_(ev->data.data(), ev->data.size(), ev->timestamp + offset_);
        continue;
      }
      if (from_poses_ && channel == lcm_.pose_channel) {
        pose_intake_(ev->data.data(), ev->data.size(), offset_);
        continue;
      }
      if (channel != lcm_.frame_channel) {
        ++skipped_;
        continue;
      }
      std::string why;
      if (!PlausibleFrame(ev->data.data(), ev->data.size(), &why) ||
          msg_.decode(ev->data.data(), 0, static_cast<int>(ev->data.size())) < 0 ||
          msg_.size != static_cast<int32_t>(msg_.data.size())) {
        *error = opt_.path + ": event " + std::to_string(ev->eventnum) + " on " +
                 std::string(channel) + ": not a kincal.frame_t";
        ++bad_frames_;
        continue;  // reported through the frame error count, replay goes on
      }
      const StatusOr<PixelFormat> format = ParsePixelFormat(msg_.pixel_format);
      if (!format.ok()) {
        ++bad_frames_;
        continue;
      }
      f->format = format.value();
      f->width = msg_.width;
      f->height = msg_.height;
      f->stride = msg_.stride;
      f->data.resize(msg_.data.size());
      std::memcpy(f->data.data(), msg_.data.data(), msg_.data.size());
      f->utime = msg_.utime + offset_;
      f->device_utime = msg_.device_utime + offset_;
      f->sequence = msg_.sequence;
      f->arrival_mono_ns = MonotonicNs();
      return SourceStatus::kFrame;
    }
    return SourceStatus::kEnd;
  }
  // Frames that could not be decoded, plus damaged stretches of the log file.
  // (Read by the health thread: atomics.)
  int64_t rejected() const override { return bad_frames_.load() + damaged_.load(); }

 private:
  // Frames, or (a log with none) the logged poses: read from a reader of its own up to the
  // first frame, so that the replay's damage counts start at zero.
  Status ChooseMeasurements() {
    std::unique_ptr<LcmLogReader> scan;
    if (Status s = LcmLogReader::Open(opt_.path, &scan); !s.ok()) {
      return Status::Error("replay: " + s.message());
    }
    int64_t poses = 0;
    LcmLogEvent ev;
    while (scan->Next(&ev)) {
      if (ev.channel == lcm_.frame_channel) return {};
      if (ev.channel == lcm_.pose_channel) ++poses;
    }
    if (poses == 0) {
      return Status::Error("replay: " + opt_.path + ": no frames on " + lcm_.frame_channel +
                           " and no poses on " + lcm_.pose_channel + ": nothing to replay");
    }
    if (!pose_intake_) {
      return Status::Error("replay: " + opt_.path + ": a log without frames (" +
                           std::to_string(poses) + " poses) needs kincald's pose intake");
    }
    from_poses_ = true;
    spdlog::info("replay: {} has no frames: its {} poses on {} are the measurements", opt_.path,
                 poses, lcm_.pose_channel);
    return {};
  }

  // Damage in the file (skipped bytes, a last event cut short) goes to the log once per
  // pass, never silently; the count is in rejected() and so in health.
  void ReportDamage() {
    if (log_->problems().size() == reported_) return;
    for (size_t i = reported_; i < log_->problems().size(); ++i)
      spdlog::warn("replay: {}", log_->problems()[i]);
    reported_ = log_->problems().size();
  }

  void Pace(int64_t utime) {
    const TimeNs due = start_mono_ + static_cast<TimeNs>(static_cast<double>(utime - first_utime_) *
                                                         1000.0 / opt_.speed);
    while (!stopped_ && MonotonicNs() < due) {
      std::this_thread::sleep_for(
          std::chrono::nanoseconds(std::min<TimeNs>(due - MonotonicNs(), 50'000'000)));
    }
  }

  const ReplayOptions opt_;
  const LcmOptions lcm_;
  ControlIntake intake_;
  PoseIntake pose_intake_;
  bool from_poses_ = false;  // the log has no frames: its poses are the measurements
  std::unique_ptr<LcmLogReader> log_;
  LcmLogEvent ev_;
  size_t reported_ = 0;
  kincal::frame_t msg_;
  TimeNs start_mono_ = 0;
  int64_t first_utime_ = INT64_MIN, last_utime_ = INT64_MIN, offset_ = 0;
  int loop_ = 0;
  int64_t events_ = 0, skipped_ = 0;
  std::atomic<int64_t> bad_frames_{0}, damaged_{0};
  std::atomic<bool> stopped_{false};
};

}  // namespace

std::unique_ptr<FrameSource> MakeReplaySource(const ReplayOptions& replay, const LcmOptions& lcm,
                                              ControlIntake controls, PoseIntake poses) {
  return std::make_unique<ReplaySource>(replay, lcm, std::move(controls), std::move(poses));
}

}  // namespace kincal::daemon
