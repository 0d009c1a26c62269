// The capture stage of kincald: frames from the source into the frame queue, each
// published (or recorded) as a frame_t when configured. A live device that fails is
// reopened with a growing wait; health carries the error meanwhile.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "daemon/bounded_queue.h"
#include "daemon/counters.h"
#include "daemon/frame_source.h"
#include "daemon/publisher.h"
#include "kincal/daemon/config.h"
#include "kincal/daemon/frame.h"

namespace kincal::daemon {

struct CaptureOptions {
  std::string frame_channel;
  bool publish_frames = false;  // to LCM; a recording gets them regardless
  FrameEncoding encoding = FrameEncoding::kRaw;
};

class CaptureStage {
 public:
  // `set_error` records the source's current error ("" when it recovered).
  CaptureStage(FrameSource* source, CaptureOptions options, Publisher* publisher,
               BoundedQueue<Frame>* out, CounterSet* counters,
               std::function<void(const std::string&)> set_error);

  // Captures until the source ends, fails for good, or `stop` is set.
  void Run(const std::atomic<bool>& stop);
  // When the last frame arrived (monotonic ns; the start time before the first).
  TimeNs last_frame_mono() const { return last_frame_mono_.load(); }
  void MarkStarted(TimeNs now_mono_ns) { last_frame_mono_.store(now_mono_ns); }

 private:
  bool ReopenWithBackoff(const std::atomic<bool>& stop);

  FrameSource& source_;
  const CaptureOptions opt_;
  Publisher& publisher_;
  BoundedQueue<Frame>& out_;
  CounterSet& counters_;
  std::function<void(const std::string&)> set_error_;
  std::atomic<TimeNs> last_frame_mono_{0};
};

}  // namespace kincal::daemon
