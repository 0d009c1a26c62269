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

#include "kincal/daemon/config.h"
#include "kincal/io/checkpoint.h"
#include "kincal/online/counters.h"

namespace kincal::daemon {

// Every counter kincald keeps, listed once: X(name, meaning): the pipeline's here, the
// online estimator's in KINCAL_ONLINE_COUNTERS (kincal/online/counters.h). Each is a field
// of DaemonCounters, of the pipeline's atomic counter set, and of kincal.health_t
// (lcm/health_t.lcm has a field of the same name for each; the health message is filled
// from this list).
#define KINCAL_PIPELINE_COUNTERS(X)                                                         \
  X(frames_captured, "frames the source delivered")                                         \
  X(frames_dropped_device, "frames the device lost (sequence gaps)")                        \
  X(frames_dropped_queue, "frames dropped by the full frame queue (live)")                  \
  X(frames_bad, "undecodable or wrong-sized frames, damaged log stretches")                 \
  X(poses_valid, "frames that gave a pose")                                                 \
  X(poses_invalid, "frames without the target")                                             \
  X(poses_published, "pose_t messages published")                                           \
  X(poses_dropped_queue, "poses dropped by the full pose queue (live)")                     \
  X(source_restarts, "the device failed and was reopened")                                  \
  X(controls_received, "control messages accepted")                                         \
  X(messages_rejected, "control messages rejected (undecodable, wrong model, not finite)")  \
  X(controls_dropped_queue, "controls dropped by the full control queue (live)")            \
  X(control_clock_steps, "the robot's clock stepped (control_stamp: mapped): new envelope") \
  X(log_events_written, "events written to the --record log")                               \
  X(log_events_lost, "events the recorder dropped (live, its queue full)")                  \
  X(guidance_skipped_busy, "estimates offered while the guidance worker was busy: skipped") \
  X(drive_legs, "guidance.drive: legs the simulated robot drove by the plan")               \
  X(drive_legs_failed, "guidance.drive: legs not planned (no estimate, no leg in view)")    \
  X(preview_published, "preview_t pictures published (preview.enabled)")                    \
  X(preview_skipped, "previews due while the preview worker was busy: skipped (live)")
#define KINCAL_DAEMON_COUNTERS(X) KINCAL_PIPELINE_COUNTERS(X) KINCAL_ONLINE_COUNTERS(X)

struct DaemonCounters {
#define KINCAL_COUNTER_FIELD(name, meaning) int64_t name = 0;
  KINCAL_DAEMON_COUNTERS(KINCAL_COUNTER_FIELD)
#undef KINCAL_COUNTER_FIELD
  double latency_p50_ms = 0, latency_p99_ms = 0, latency_max_ms = 0;  // whole run
  // Control receive delay beyond the least (robot.control_stamp: mapped), whole run; -1:
  // not measured (other stamp choices, or no sender_utime in the messages).
  double control_jitter_p95_ms = -1, control_jitter_max_ms = -1;
};

class Daemon {
 public:
  // Validates the config and opens everything (the camera, floor and target files, the
  // source, the checkpoint resumed, the output locks, LCM, the log); an error names what
  // failed. The only way to make a Daemon.
  static StatusOr<std::unique_ptr<Daemon>> Create(DaemonConfig config);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Runs until the source ends or Stop() is called; then drains the queues, publishes
  // the final estimate, writes the checkpoint and closes the log. Returns 0 on success, 1
  // when the source could not start or a pipeline thread failed (the reason is logged).
  int Run();
  // Thread-safe; may be called before Run() returns from any thread.
  void Stop();

  // The calibration: the last good batch calibration (source "batch"), the filter's
  // estimate before there is one (after Run(): the final one, as checkpointed).
  Checkpoint Estimate() const;
  // The filter's own latest estimate (the real-time tier, source "filter").
  Checkpoint FilterEstimate() const;
  DaemonCounters counters() const;

 private:
  explicit Daemon(DaemonConfig config);  // throws inside daemon.cc only (Create catches)
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kincal::daemon
