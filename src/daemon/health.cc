#include "daemon/health.h"

#include <spdlog/spdlog.h>

#include <kincal/params_t.hpp>

#include "daemon/messages.h"

namespace kincal::daemon {
namespace {

class Problems {
 public:
  void Add(const std::string& what) { text_ += (text_.empty() ? "" : "; ") + what; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

// What went wrong in the pipeline since the last message: the source, frames, queues, log.
void PipelineProblems(const DaemonCounters& now, const DaemonCounters& prev, const HealthStatus& s,
                      Problems* p) {
  if (!s.source_error.empty()) p->Add("source: " + s.source_error);
  if (now.frames_bad > prev.frames_bad) {
    // A frame the detector could not use says why; events the source itself could not
    // decode (a damaged or foreign log) have no frame to speak of.
    p->Add("bad frames: " + (s.last_frame_error.empty()
                                 ? std::to_string(now.frames_bad - prev.frames_bad) +
                                       " the source could not decode (damaged or foreign data)"
                                 : s.last_frame_error));
  }
  if (!s.source_done && s.since_last_frame_ns > HealthReporter::kNoFramesNs)
    p->Add("no frames for 2 s");
  if (now.frames_dropped_queue > prev.frames_dropped_queue) {
    p->Add("frame queue full: detection is too slow");
  }
  if (now.poses_dropped_queue > prev.poses_dropped_queue) {
    p->Add("pose queue full: the filter is too slow");
  }
  if (now.controls_dropped_queue > prev.controls_dropped_queue) {
    p->Add("control queue full: the filter is too slow");
  }
  if (now.frames_dropped_device > prev.frames_dropped_device) p->Add("the device dropped frames");
  if (now.log_events_lost > prev.log_events_lost) p->Add("log events lost");
}

// ... and in the estimate and its inputs: resets, clocks, status, target, controls.
void EstimateProblems(const DaemonCounters& now, const DaemonCounters& prev, const HealthStatus& s,
                      Problems* p) {
  if (now.filter_resets > prev.filter_resets) {
    p->Add("filter diverged and was restarted from a batch fit");
  }
  if (now.time_resets > prev.time_resets) p->Add("a clock jumped back: new time base");
  if (now.control_clock_steps > prev.control_clock_steps) {
    p->Add("the robot's clock stepped (sender_utime): control stamps re-mapped");
  }
  if (s.filter_status == kincal::params_t::STATUS_DIVERGED) {
    p->Add("filter diverged: poses fail the innovation gate");
  } else if (s.filter_status == kincal::params_t::STATUS_MODEL_INADEQUATE) {
    p->Add("the model does not fit the motion: " + s.model_check_evidence);
  }
  if (now.frames_captured > 0 && s.seconds_without_target > s.no_target_warn_s) {
    p->Add(fmt::format("no target seen for {:.1f} s", s.seconds_without_target));
  }
  if (now.frames_out_of_order > prev.frames_out_of_order) {
    p->Add("frames with repeated or earlier timestamps");
  }
  if (now.messages_rejected > prev.messages_rejected) {
    p->Add("rejected control messages (last: " + s.last_reject + ")");
  }
  if (!s.recorder_error.empty()) p->Add(s.recorder_error);
  if (s.expects_lcm_controls && now.controls_received == 0 && now.frames_captured > 0) {
    p->Add("no controls received on " + s.controls_channel);
  }
}

}  // namespace

std::string SummaryLine(const DaemonCounters& c) {
  return fmt::format(
      "{} frames ({} dropped by the device, {} by the queue, {} bad, {} out of order), "
      "{} valid poses ({} dropped by the queue), {} updates, {} gated, {} runs, {} filter "
      "resets, {} time resets, {} source restarts; {} controls ({} rejected, {} out of order, "
      "{} late, {} dropped by the queue); log {} written / {} lost; latency p50 {:.3f} ms p99 "
      "{:.3f} ms{}{}",
      c.frames_captured, c.frames_dropped_device, c.frames_dropped_queue, c.frames_bad,
      c.frames_out_of_order, c.poses_valid, c.poses_dropped_queue, c.updates, c.poses_gated,
      c.run_resets + (c.updates > 0 ? 1 : 0), c.filter_resets, c.time_resets, c.source_restarts,
      c.controls_received, c.messages_rejected, c.controls_out_of_order, c.controls_late,
      c.controls_dropped_queue, c.log_events_written, c.log_events_lost, c.latency_p50_ms,
      c.latency_p99_ms,
      c.control_jitter_p95_ms < 0
          ? std::string()
          : fmt::format("; control receive jitter p95 {:.1f} ms max {:.1f} ms, {} clock steps",
                        c.control_jitter_p95_ms, c.control_jitter_max_ms, c.control_clock_steps),
      c.preview_published + c.preview_skipped == 0
          ? std::string()
          : fmt::format("; preview {} published, {} skipped (the preview worker was busy)",
                        c.preview_published, c.preview_skipped));
}

void HealthReporter::Build(const DaemonCounters& now, const HealthStatus& s, double period_s,
                           int64_t utime, kincal::health_t* h) {
  *h = kincal::health_t{};
  h->schema_version = 8;
  h->utime = utime;
  h->source = s.source_name;
  h->frame_rate_hz = static_cast<double>(now.frames_captured - prev_.frames_captured) / period_s;
  FillHealthCounters(now, h);
  h->latency_p50_ms = s.latency_p50_ms;
  h->latency_p99_ms = s.latency_p99_ms;
  h->filter_status = static_cast<int8_t>(s.filter_status);
  h->seconds_without_target = s.seconds_without_target;
  h->control_jitter_p95_ms = now.control_jitter_p95_ms;
  h->control_jitter_max_ms = now.control_jitter_max_ms;

  Problems p;
  PipelineProblems(now, prev_, s, &p);
  EstimateProblems(now, prev_, s, &p);
  h->ok = p.text().empty() ? 1 : 0;
  h->message = p.text();
  prev_ = now;
}

bool HealthReporter::Log(const std::string& message, TimeNs now_mono_ns) {
  if (message == logged_ && now_mono_ns - logged_at_ns_ <= kRepeatNs) return false;
  const bool cleared = message.empty() && !logged_.empty();
  if (!message.empty()) spdlog::warn("health: {}", message);
  if (cleared) spdlog::info("health: ok");
  logged_ = message;
  logged_at_ns_ = now_mono_ns;
  return !message.empty() || cleared;
}

namespace {

// Why there is no estimate: the filter never started.
std::string NeverStarted(const EndOfRun& e) {
  const DaemonCounters& c = e.counters;
  return fmt::format(
      "the filter never started ({} valid poses; {} control messages accepted, {} rejected{})",
      c.poses_valid, c.controls_received, c.messages_rejected,
      e.last_reject.empty() ? "" : ", the last: " + e.last_reject);
}

}  // namespace

std::string EndOfRunError(const EndOfRun& e) {
  if (!e.checkpoint_error.empty())
    return "the final checkpoint was not written: " + e.checkpoint_error;
  // A log of frames alone (no controls came, none asked for a checkpoint) gives poses only.
  if (e.has_estimate || !e.source_ended) return "";
  if (e.checkpoint_path.empty() && e.counters.messages_rejected == 0) return "";
  return "the run ended without an estimate" +
         (e.checkpoint_path.empty() ? "" : " (" + e.checkpoint_path + " not written)") + ": " +
         NeverStarted(e);
}

int EndOfRunCode(const EndOfRun& e) {
  const std::string error = EndOfRunError(e);
  if (!error.empty()) spdlog::error("kincald: {}", error);
  if (error.empty() && !e.has_estimate && !e.checkpoint_path.empty())
    spdlog::warn("kincald: stopped with no estimate: {} not written: {}", e.checkpoint_path,
                 NeverStarted(e));
  return error.empty() && e.source_error.empty() ? 0 : 1;
}

}  // namespace kincal::daemon
