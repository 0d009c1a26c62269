// Decoding and checking of incoming control messages.
#include "daemon/control_input.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <kincal/controls_t.hpp>

#include "kincal/io/lcm_guard.h"

namespace kincal::daemon {

bool DecodeControls(const void* data, size_t n, const KinematicModel& model, bool use_sender_stamp,
                    int64_t receive_utime, ControlSample* out, std::string* why) {
  thread_local kincal::controls_t m;
  if (n > (1u << 16)) {
    *why = "message of " + std::to_string(n) + " bytes is too large for kincal.controls_t";
    return false;
  }
  if (!PlausibleControls(data, n, kMaxControls, why)) return false;
  try {
    if (m.decode(data, 0, static_cast<int>(n)) < 0) {
      *why = "not a kincal.controls_t";
      return false;
    }
  } catch (const std::exception& e) {  // lcm-gen's decoder on input the checks above missed
    *why = std::string("not a kincal.controls_t (") + e.what() + ")";
    return false;
  }
  if (m.model != model.name()) {
    *why = "controls for model '" + m.model + "', expected '" + std::string(model.name()) + "'";
    return false;
  }
  if (use_sender_stamp && m.sender_utime <= 0) {
    *why = "no sender_utime, but robot.control_stamp is sender";
    return false;
  }
  ControlSample s;
  s.receive_utime = receive_utime;
  s.sender_utime = m.sender_utime;
  s.utime = use_sender_stamp ? m.sender_utime : receive_utime;
  std::array<bool, kMaxControls> seen{};
  for (int i = 0; i < m.num_controls; ++i) {
    const std::string& name = m.names[static_cast<size_t>(i)];
    const int k = model.ControlIndex(name);
    if (k < 0) {
      *why = "'" + name + "' is not a control of model '" + std::string(model.name()) + "'";
      return false;
    }
    const double v = m.values[static_cast<size_t>(i)];
    const std::string& unit = model.controls()[static_cast<size_t>(k)].unit;
    const double limit = PlausibleControlLimit(unit);
    if (!std::isfinite(v) || std::abs(v) > limit) {
      *why = "control '" + name + "' = " + std::to_string(v) +
             ": expected a finite value within +-" + std::to_string(limit) + " " + unit;
      return false;
    }
    s.values[static_cast<size_t>(k)] = v;
    seen[static_cast<size_t>(k)] = true;
  }
  for (int k = 0; k < model.num_controls(); ++k) {
    if (!seen[static_cast<size_t>(k)]) {
      *why = "control '" + model.controls()[static_cast<size_t>(k)].name + "' missing";
      return false;
    }
  }
  *out = s;
  return true;
}

void ControlReceiver::OnMessage(const void* data, size_t n, int64_t receive_utime) {
  publisher_.Record(channel_, receive_utime, data, n);
  ControlSample s;
  thread_local std::string why;
  if (!DecodeControls(data, n, model_, stamp_ == ControlStamp::kSender, receive_utime, &s, &why)) {
    if (counters_.messages_rejected.fetch_add(1) == 0) {
      spdlog::warn("rejected a control message: {}", why);
    }
    std::lock_guard lock(mu_);
    last_reject_ = why;
    return;
  }
  if (stamp_ == ControlStamp::kMapped) {
    std::lock_guard lock(mu_);
    if (s.sender_utime > 0) {
      const int64_t steps = clock_.steps();
      s.utime = clock_.Map(s.sender_utime, receive_utime);
      if (clock_.steps() > steps) counters_.control_clock_steps.fetch_add(1);
    } else if (without_sender_stamp_++ == 0) {
      spdlog::warn(
          "control messages without sender_utime: stamped on receipt, so a loaded receiver's "
          "delays reach the filter (robot.control_stamp: mapped needs the robot's own stamp)");
    }
  }
  counters_.controls_received.fetch_add(1);
  out_.Push(s);
}

ControlTiming ControlReceiver::timing() const {
  std::lock_guard lock(mu_);
  ControlTiming t;
  t.without_sender_stamp = without_sender_stamp_;
  if (stamp_ == ControlStamp::kMapped && clock_.measured() > 0) {
    t.jitter_p95_ms = clock_.jitter_p95_ms();
    t.jitter_max_ms = clock_.jitter_max_ms();
  }
  return t;
}

std::string ControlReceiver::last_reject() const {
  std::lock_guard lock(mu_);
  return last_reject_;
}

}  // namespace kincal::daemon
