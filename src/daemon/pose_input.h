// Logged pose measurements (raw kincal.pose_t bytes from a log without frames: motion
// capture imported by `kincal import`) into the filter thread's pose queue, as the
// detection stage hands over the poses it measures in frames. Outside data: the message
// is decoded by lcm-gen's fixed-size decoder, then its values are checked.
#pragma once

#include <array>
#include <mutex>
#include <string>

#include "daemon/bounded_queue.h"
#include "daemon/counters.h"
#include "daemon/publisher.h"
#include "kincal/online/samples.h"

namespace kincal::daemon {

// False (with the reason in *why) for anything that is not a pose_t with finite values.
// Its stamps move by `utime_shift`. A covariance that is not symmetric positive definite
// (a pose logged without one: zeros) becomes diag(sigma^2).
bool DecodeLoggedPose(const void* data, size_t n, int64_t utime_shift,
                      const std::array<double, 3>& sigma, PoseSample* out, std::string* why);

// Every logged pose comes through here: decoded, counted as the detection stage counts
// its poses, published on the pose channel (so that outputs and a recording of the replay
// hold it as a camera run's do), and queued for the filter thread. Thread-safe.
class PoseReceiver {
 public:
  PoseReceiver(std::string channel, std::array<double, 3> sigma, Publisher* publisher,
               BoundedQueue<PoseSample>* out, CounterSet* counters)
      : channel_(std::move(channel)),
        sigma_(sigma),
        publisher_(*publisher),
        out_(*out),
        counters_(*counters) {}

  void OnMessage(const void* data, size_t n, int64_t utime_shift);
  std::string last_reject() const;

 private:
  const std::string channel_;
  const std::array<double, 3> sigma_;
  Publisher& publisher_;
  BoundedQueue<PoseSample>& out_;
  CounterSet& counters_;
  mutable std::mutex mu_;  // guards what follows
  std::string last_reject_;
};

}  // namespace kincal::daemon
