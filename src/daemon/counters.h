// The pipeline's counters as atomics (each written by one thread, read by the health
// thread), generated from the one list KINCAL_DAEMON_COUNTERS. Counters that a component
// keeps itself (a source's sequence gaps, a queue's drops, the recorder's events) are read
// from it when a snapshot is taken.
#pragma once

#include <atomic>
#include <cstdint>

#include "kincal/daemon/daemon.h"
#include "kincal/online/counters.h"

namespace kincal::daemon {

// The online estimator's counters are the base (the filter stage writes them).
struct CounterSet : OnlineCounters {
#define KINCAL_COUNTER_ATOMIC(name, meaning) std::atomic<int64_t> name{0};
  KINCAL_PIPELINE_COUNTERS(KINCAL_COUNTER_ATOMIC)
#undef KINCAL_COUNTER_ATOMIC

  // The values counted here (components' own counters are added by the caller).
  DaemonCounters Load() const {
    DaemonCounters c;
#define KINCAL_COUNTER_LOAD(name, meaning) c.name = name.load(std::memory_order_relaxed);
    KINCAL_DAEMON_COUNTERS(KINCAL_COUNTER_LOAD)
#undef KINCAL_COUNTER_LOAD
    return c;
  }
};

}  // namespace kincal::daemon
