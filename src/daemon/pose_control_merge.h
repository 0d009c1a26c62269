// The filter thread's loop: poses and controls merged in time order. A pose goes to the
// filter stage once the controls up to its time are in, or the controls have ended, or
// (live) it has waited robot.max_control_delay_s. Poses that wait are held in a ring of
// bounded size; when it is full the oldest goes with the controls there are.
#pragma once

#include <atomic>

#include "daemon/bounded_queue.h"
#include "kincal/online/filter_stage.h"
#include "kincal/online/samples.h"

namespace kincal::daemon {

struct MergeInputs {
  BoundedQueue<PoseSample>* poses = nullptr;
  BoundedQueue<ControlSample>* controls = nullptr;
  const std::atomic<bool>* controls_done = nullptr;  // no control will arrive any more
  const std::atomic<bool>* stop = nullptr;
  bool lossless = false;            // replay --fast: wait for data, never for time
  TimeNs max_control_delay_ns = 0;  // live: how long a pose waits for its controls
  size_t max_pending_poses = 256;   // poses held waiting for controls
};

// Runs until the poses have ended (and, lossless, the controls too), then Finish()es.
void RunPoseControlMerge(FilterStage* stage, const MergeInputs& in);

}  // namespace kincal::daemon
