// One incoming robot control message (raw kincal.controls_t bytes from LCM, the simulated
// robot or a log), checked and turned into a ControlSample in the model's channel order.
// Outside data: the length fields are checked before lcm-gen's decoder runs, then the
// model, the channel names and the values. Allocation-free after the first calls.
#pragma once

#include <string>

#include "kincal/daemon/samples.h"
#include "kincal/model.h"

namespace kincal::daemon {

// False (with the reason in *why) for anything that is not a complete, finite set of
// `model`'s controls. `use_sender_stamp` picks the message's sender_utime as the sample's
// time instead of `receive_utime`.
bool DecodeControls(const void* data, size_t n, const KinematicModel& model, bool use_sender_stamp,
                    int64_t receive_utime, ControlSample* out, std::string* why);

}  // namespace kincal::daemon
