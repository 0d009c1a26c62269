// kincald's pipeline: capture thread -> bounded queue -> detection/pose thread ->
// bounded queue -> filter thread -> LCM publisher, with robot controls arriving over LCM
// (or from the source, for simulation and replay) and a recorder thread writing every
// input and output to an LCM log. The main thread publishes health at 1 Hz.
//
// Policies: live, the frame and pose queues drop their oldest entry when full (fresh data
// matters more than old) and the recorder drops new events (counted as lost); in lossless
// mode (replay --fast, simulation as fast as possible) every queue blocks instead, the
// filter consumes poses and controls merged in time order, and two runs give bit-identical
// estimates. Every drop is counted and published in kincal.health_t.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "kincal/daemon/checkpoint.h"
#include "kincal/daemon/config.h"

namespace kincal::daemon {

struct DaemonCounters {
  int64_t frames_captured = 0;
  int64_t frames_dropped_device = 0;
  int64_t frames_dropped_queue = 0;
  int64_t frame_errors = 0;
  int64_t poses_valid = 0;
  int64_t poses_invalid = 0;
  int64_t poses_dropped_queue = 0;
  int64_t frames_out_of_order = 0;  // pose time repeated or earlier than the last: not used
  int64_t poses_gated = 0;          // innovation too large: not used
  int64_t filter_resets = 0;        // divergence: restarted from a batch fit
  int64_t time_resets = 0;          // a clock jumped back: new time base
  int64_t discarded_at_reset = 0;   // poses/controls still on the old time base after one
  int64_t source_restarts = 0;      // the device failed and was reopened
  int64_t controls_late = 0;        // older than the filter's time
  int64_t updates = 0;
  int64_t run_resets = 0;
  int64_t controls_received = 0;
  int64_t controls_rejected = 0;    // undecodable, wrong model, not finite
  int64_t controls_out_of_order = 0;
  int64_t controls_dropped_queue = 0;
  int64_t log_events_written = 0;
  int64_t log_events_lost = 0;
  double latency_p50_ms = 0, latency_p99_ms = 0, latency_max_ms = 0;  // whole run
};

class Daemon {
 public:
  // Validates the config and opens everything (LCM, log, source, checkpoint); throws
  // std::runtime_error with a message naming what failed.
  explicit Daemon(DaemonConfig config);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Runs until the source ends or Stop() is called; then drains the queues, publishes
  // the final estimate, writes the checkpoint and closes the log. Returns 0 on success.
  int Run();
  // Thread-safe; may be called before Run() returns from any thread.
  void Stop();

  // The current estimate (after Run(): the final one).
  Checkpoint Estimate() const;
  DaemonCounters counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kincal::daemon
