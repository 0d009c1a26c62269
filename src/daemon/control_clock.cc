// The lower envelope of receive - sender offsets over a sliding window.
#include "daemon/control_clock.h"

#include <algorithm>

namespace kincal::daemon {

void ControlClock::Restart(Candidate c) {
  head_ = 0;
  size_ = 0;
  Push(c);
}

void ControlClock::Push(Candidate c) {
  while (size_ > 0 && back().offset_us >= c.offset_us) --size_;
  if (size_ == kCapacity) {  // more candidates than the ring holds: the oldest goes
    head_ = (head_ + 1) % kCapacity;
    --size_;
  }
  ring_[(head_ + size_) % kCapacity] = c;
  ++size_;
}

int64_t ControlClock::Map(int64_t sender_utime, int64_t receive_utime) {
  const Candidate c{sender_utime, receive_utime - sender_utime};
  // The robot's clock went back, or its offset jumped beyond any delay: a new envelope.
  if (size_ > 0 &&
      (sender_utime < back().sender_utime || c.offset_us - front().offset_us > opt_.max_jitter_us ||
       c.offset_us < front().offset_us - opt_.max_jitter_us)) {
    ++steps_;
    Restart(c);
  } else {
    Push(c);
  }
  while (size_ > 1 && front().sender_utime < sender_utime - opt_.window_us) {
    head_ = (head_ + 1) % kCapacity;
    --size_;
  }
  const int64_t floor = front().offset_us;
  jitter_.Add(static_cast<double>(c.offset_us - floor) / 1000.0);
  // Never earlier than the last stamp given (the floor can rise as old minima leave the
  // window, and fall when a faster message arrives), never later than the receipt.
  int64_t stamp = sender_utime + floor;
  if (last_stamp_ != INT64_MIN) stamp = std::max(stamp, last_stamp_);
  stamp = std::min(stamp, receive_utime);
  last_stamp_ = stamp;
  return stamp;
}

}  // namespace kincal::daemon
