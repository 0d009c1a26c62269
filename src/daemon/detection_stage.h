// The detection thread of kincald: frames from the frame queue through the pose stage,
// each pose published at once (pose_t, and markers_t when configured: the frame-to-publish
// latency is measured here) and handed to the filter thread.
#pragma once

#include <mutex>
#include <string>

#include "daemon/bounded_queue.h"
#include "daemon/counters.h"
#include "daemon/latency_histogram.h"
#include "daemon/pose_stage.h"
#include "daemon/preview.h"
#include "daemon/publisher.h"

namespace kincal::daemon {

struct DetectionOptions {
  std::string pose_channel, markers_channel;
  bool publish_markers = false;
  double marker_sigma_px = 0.05;  // published with each marker
};

class DetectionStage {
 public:
  // `preview` (may be null: preview.enabled false) is offered every frame after its pose
  // went out.
  DetectionStage(PoseStage* stage, DetectionOptions options, Publisher* publisher,
                 BoundedQueue<Frame>* in, BoundedQueue<PoseSample>* out, CounterSet* counters,
                 PreviewStage* preview = nullptr);

  // Until the frame queue is closed and empty; then closes the pose queue.
  void Run();

  // For health: the last frame error, and latency percentiles since the last call (window)
  // or over the run (total).
  struct Status {
    std::string last_frame_error;
    double window_p50_ms = 0, window_p99_ms = 0;
    double total_p50_ms = 0, total_p99_ms = 0, total_max_ms = 0;
    double seconds_without_target = 0;  // frame time since the last pose (or the first frame)
  };
  Status TakeStatus(bool reset_window);

 private:
  PoseStage& stage_;
  const DetectionOptions opt_;
  Publisher& publisher_;
  BoundedQueue<Frame>& in_;
  BoundedQueue<PoseSample>& out_;
  CounterSet& counters_;
  PreviewStage* const preview_;
  std::mutex mu_;  // guards what follows
  std::string last_frame_error_;
  LatencyHistogram latency_total_, latency_window_;
  int64_t last_target_utime_ = -1, last_frame_utime_ = -1;
};

}  // namespace kincal::daemon
