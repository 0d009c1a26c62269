#include "daemon/capture_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <kincal/frame_t.hpp>
#include <thread>

#include "daemon/messages.h"
#include "daemon/sources.h"

namespace kincal::daemon {
namespace {

// A live device that failed is reopened after 0.25 s, 0.5 s, ... up to 5 s between tries.
constexpr double kReopenFirstWaitS = 0.25;
constexpr double kReopenMaxWaitS = 5.0;
// How long one wait for a frame lasts before `stop` is looked at again.
constexpr int kFrameWaitMs = 100;

}  // namespace

CaptureStage::CaptureStage(FrameSource* source, CaptureOptions options, Publisher* publisher,
                           BoundedQueue<Frame>* out, CounterSet* counters,
                           std::function<void(const std::string&)> set_error)
    : source_(*source),
      opt_(std::move(options)),
      publisher_(*publisher),
      out_(*out),
      counters_(*counters),
      set_error_(std::move(set_error)) {}

void CaptureStage::Run(const std::atomic<bool>& stop) {
  const bool can_reopen = source_.capabilities().can_reopen;
  const bool frame_messages = opt_.publish_frames || publisher_.recorder() != nullptr;
  Frame f;
  kincal::frame_t msg;
  std::vector<uint8_t> png;
  std::string error;
  while (!stop.load()) {
    const SourceStatus st = source_.Next(&f, kFrameWaitMs, &error);
    if (st == SourceStatus::kEnd) break;
    if (st == SourceStatus::kTimeout) continue;
    if (st == SourceStatus::kError) {
      set_error_(error);
      spdlog::error("source {}: {}", source_.name(), error);
      // Asked again: a source may find it cannot be reopened (a vanished libcamera camera).
      if (!can_reopen || !source_.capabilities().can_reopen || !ReopenWithBackoff(stop)) break;
      continue;
    }
    counters_.frames_captured.fetch_add(1);
    last_frame_mono_.store(MonotonicNs());
    if (frame_messages) {
      // A frame that does not decode is recorded raw; the pose stage counts and reports it.
      (void)FillFrameMessage(f, opt_.encoding, &png, &msg);
      publisher_.Publish(opt_.frame_channel, f.utime, msg, opt_.publish_frames);
    }
    out_.Push(f);
  }
  out_.Close();
}

// Closes the device and opens it again, waiting longer each time, until it is back or
// the daemon is stopped.
bool CaptureStage::ReopenWithBackoff(const std::atomic<bool>& stop) {
  double wait_s = kReopenFirstWaitS;
  while (!stop.load()) {
    const TimeNs until = MonotonicNs() + SecondsToNs(wait_s);
    while (!stop.load() && MonotonicNs() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (stop.load()) return false;
    const Status reopened = source_.Reopen();
    if (reopened.ok()) {
      counters_.source_restarts.fetch_add(1);
      set_error_("");
      spdlog::info("source {}: reopened, capturing again", source_.name());
      return true;
    }
    wait_s = std::min(kReopenMaxWaitS, 2 * wait_s);
    set_error_(reopened.message() + " (retrying every " + std::to_string(wait_s).substr(0, 4) +
               " s)");
  }
  return false;
}

}  // namespace kincal::daemon
