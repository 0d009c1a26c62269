// What the device sources (V4L2, libcamera) share: counting the frames a device lost from
// gaps in its sequence numbers.
#pragma once

#include <atomic>
#include <cstdint>

#include "daemon/frame_source.h"

namespace kincal::daemon {

// Frames lost by a device, from gaps in the sequence numbers of the frames it delivered.
// Observe() on the capture thread; drops() from any thread.
class SequenceGaps {
 public:
  void Observe(uint32_t sequence) {
    if (have_last_ && sequence > last_ + 1) drops_.fetch_add(sequence - last_ - 1);
    last_ = sequence;
    have_last_ = true;
  }
  // A reopened device numbers its frames anew.
  void Restart() { have_last_ = false; }
  int64_t drops() const { return drops_.load(); }

 private:
  std::atomic<int64_t> drops_{0};
  uint32_t last_ = 0;
  bool have_last_ = false;
};

}  // namespace kincal::daemon
