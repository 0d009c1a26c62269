// One incoming robot control message (raw kincal.controls_t bytes from LCM, the simulated
// robot or a log), checked and turned into a ControlSample in the model's channel order.
// Outside data: the length fields are checked before lcm-gen's decoder runs, then the
// model, the channel names and the values. Allocation-free after the first calls.
#pragma once

#include <mutex>
#include <string>

#include "daemon/bounded_queue.h"
#include "daemon/counters.h"
#include "daemon/publisher.h"
#include "kincal/daemon/samples.h"
#include "kincal/model.h"

namespace kincal::daemon {

// False (with the reason in *why) for anything that is not a complete, finite set of
// `model`'s controls. `use_sender_stamp` picks the message's sender_utime as the sample's
// time instead of `receive_utime`.
bool DecodeControls(const void* data, size_t n, const KinematicModel& model, bool use_sender_stamp,
                    int64_t receive_utime, ControlSample* out, std::string* why);

// Every control message, from LCM, the simulated robot or a log, comes through here: it is
// recorded as received, decoded, counted, and queued for the filter thread. Thread-safe.
class ControlReceiver {
 public:
  ControlReceiver(const KinematicModel& model, bool use_sender_stamp, std::string channel,
                  Publisher* publisher, BoundedQueue<ControlSample>* out, CounterSet* counters)
      : model_(model),
        use_sender_stamp_(use_sender_stamp),
        channel_(std::move(channel)),
        publisher_(*publisher),
        out_(*out),
        counters_(*counters) {}

  void OnMessage(const void* data, size_t n, int64_t receive_utime);
  std::string last_reject() const;

 private:
  const KinematicModel& model_;
  const bool use_sender_stamp_;
  const std::string channel_;
  Publisher& publisher_;
  BoundedQueue<ControlSample>& out_;
  CounterSet& counters_;
  mutable std::mutex mu_;
  std::string last_reject_;
};

}  // namespace kincal::daemon
