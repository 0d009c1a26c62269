// Control messages stamped on the robot's clock, mapped onto the daemon's receive clock.
//
// A message sent at s (robot clock) is received at r = s + c + d: c is the clock offset plus
// the least transport delay, d >= 0 the extra delay a loaded receiver adds (scheduling,
// queues). The lower envelope of r - s over a sliding window estimates c; the message is
// stamped s + c (never later than r), so receive-time jitter does not reach the filter.
// What is left is a constant latency, which the time_offset effect absorbs. d is the
// measured jitter, reported as p95 and maximum. A jump of r - s beyond `max_jitter` means
// the robot's clock stepped (reboot, NTP): the envelope restarts from that message.
// Fixed memory (a ring of `kCapacity` candidates); no allocation after construction.
#pragma once

#include <array>
#include <cstdint>

#include "daemon/latency_histogram.h"

namespace kincal::daemon {

struct ControlClockOptions {
  int64_t window_us = 10'000'000;     // the envelope's span of sender time
  int64_t max_jitter_us = 1'000'000;  // beyond this, the robot's clock is taken to have stepped
};

class ControlClock {
 public:
  explicit ControlClock(ControlClockOptions opt = {}) : opt_(opt) {}

  // The message's time on the receive clock. `sender_utime` > 0.
  int64_t Map(int64_t sender_utime, int64_t receive_utime);

  double jitter_p95_ms() const { return jitter_.Percentile(0.95); }
  double jitter_max_ms() const { return jitter_.max_ms(); }
  int64_t steps() const { return steps_; }
  int64_t measured() const { return jitter_.count(); }

 private:
  struct Candidate {
    int64_t sender_utime;
    int64_t offset_us;  // receive - sender
  };
  static constexpr size_t kCapacity = 1024;

  void Push(Candidate c);
  void Restart(Candidate c);
  Candidate& front() { return ring_[head_]; }
  Candidate& back() { return ring_[(head_ + size_ - 1) % kCapacity]; }

  ControlClockOptions opt_;
  // Candidates for the window's minimum offset: increasing in sender time and in offset
  // (a monotonic deque), the minimum at the front.
  std::array<Candidate, kCapacity> ring_{};
  size_t head_ = 0, size_ = 0;
  int64_t last_stamp_ = INT64_MIN;
  int64_t steps_ = 0;
  LatencyHistogram jitter_;
};

}  // namespace kincal::daemon
