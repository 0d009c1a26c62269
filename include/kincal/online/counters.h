// What the online estimator counts, listed once: X(name, meaning). kincald's counters
// (KINCAL_DAEMON_COUNTERS, kincal/daemon/daemon.h) include these, so each is also a field
// of kincal.health_t.
#pragma once

#include <atomic>
#include <cstdint>

#define KINCAL_ONLINE_COUNTERS(X)                                                            \
  X(frames_out_of_order, "pose time repeated or earlier than the last: not used")            \
  X(poses_gated, "poses that failed the innovation gate: not used")                          \
  X(poses_downweighted, "poses beyond the gate in a streak: used with a widened covariance") \
  X(updates, "filter updates")                                                               \
  X(run_resets, "new runs: a gap between poses longer than filter.max_pose_gap_s")           \
  X(filter_resets, "divergence: the filter restarted from a batch fit")                      \
  X(time_resets, "a clock jumped back: new time base, parameters kept")                      \
  X(discarded_at_reset, "poses and controls still on the old time base after one")           \
  X(effects_added, "effects added online (robot.effects: auto)")                             \
  X(effects_removed, "effects removed again: a later batch no longer supported them")        \
  X(batch_runs, "batch calibrations run (calibration.every_s and at shutdown)")              \
  X(batch_failed, "batch calibrations that failed: the last good one stays")                 \
  X(filter_recentres, "the filter disagreed with a batch calibration and was re-centred")    \
  X(batch_shutdown_ms, "wall time at shutdown spent on the last batch calibrations, ms")     \
  X(controls_out_of_order, "controls older than the newest one: ignored")                    \
  X(controls_late, "controls older than the filter's time: applied from then on")

namespace kincal {

// The counts at one moment.
struct OnlineCounts {
#define KINCAL_ONLINE_COUNT_FIELD(name, meaning) int64_t name = 0;
  KINCAL_ONLINE_COUNTERS(KINCAL_ONLINE_COUNT_FIELD)
#undef KINCAL_ONLINE_COUNT_FIELD
};

// The online estimator's counters as atomics: written by the thread that runs the
// estimator, read by any (health).
struct OnlineCounters {
#define KINCAL_ONLINE_COUNTER_ATOMIC(name, meaning) std::atomic<int64_t> name{0};
  KINCAL_ONLINE_COUNTERS(KINCAL_ONLINE_COUNTER_ATOMIC)
#undef KINCAL_ONLINE_COUNTER_ATOMIC

  OnlineCounts LoadOnline() const {
    OnlineCounts c;
#define KINCAL_ONLINE_COUNTER_LOAD(name, meaning) c.name = name.load(std::memory_order_relaxed);
    KINCAL_ONLINE_COUNTERS(KINCAL_ONLINE_COUNTER_LOAD)
#undef KINCAL_ONLINE_COUNTER_LOAD
    return c;
  }
};

}  // namespace kincal
