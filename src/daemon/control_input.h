// One incoming robot control message (raw kincal.controls_t bytes from LCM, the simulated
// robot or a log), checked and turned into a ControlSample in the model's channel order.
// Outside data: the length fields are checked before lcm-gen's decoder runs, then the
// model, the channel names and the values. Allocation-free after the first calls.
#pragma once

#include <mutex>
#include <string>

#include "daemon/bounded_queue.h"
#include "daemon/control_clock.h"
#include "daemon/counters.h"
#include "daemon/publisher.h"
#include "kincal/daemon/config.h"
#include "kincal/model.h"
#include "kincal/online/samples.h"

namespace kincal::daemon {

// False (with the reason in *why) for anything that is not a complete, finite set of
// `model`'s controls. `use_sender_stamp` picks the message's sender_utime as the sample's
// time instead of `receive_utime` (and requires one).
bool DecodeControls(const void* data, size_t n, const KinematicModel& model, bool use_sender_stamp,
                    int64_t receive_utime, ControlSample* out, std::string* why);

// What the receiver has seen of the control messages' timing (robot.control_stamp: mapped).
struct ControlTiming {
  double jitter_p95_ms = -1.0;  // receive delay beyond the least, p95; -1: not measured
  double jitter_max_ms = -1.0;
  int64_t without_sender_stamp = 0;  // stamped on receipt: their jitter is not removed
};

// Every control message, from LCM, the simulated robot or a log, comes through here: it is
// recorded as received, decoded, counted, and queued for the filter thread. Thread-safe.
class ControlReceiver {
 public:
  ControlReceiver(const KinematicModel& model, ControlStamp stamp, std::string channel,
                  Publisher* publisher, BoundedQueue<ControlSample>* out, CounterSet* counters)
      : model_(model),
        stamp_(stamp),
        channel_(std::move(channel)),
        publisher_(*publisher),
        out_(*out),
        counters_(*counters) {}

  void OnMessage(const void* data, size_t n, int64_t receive_utime);
  std::string last_reject() const;
  ControlTiming timing() const;

 private:
  const KinematicModel& model_;
  const ControlStamp stamp_;
  const std::string channel_;
  Publisher& publisher_;
  BoundedQueue<ControlSample>& out_;
  CounterSet& counters_;
  mutable std::mutex mu_;
  std::string last_reject_;
  ControlClock clock_;  // under mu_
  int64_t without_sender_stamp_ = 0;
};

}  // namespace kincal::daemon
