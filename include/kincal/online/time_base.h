// The filter's time base: which poses and controls belong to it, and when a clock has
// jumped back so that a new one must start. Thread-free and clock-free: times are the
// pipeline's (ns, recorded realtime, `utime * 1000`), and the caller supplies the decisions'
// inputs, so that a `--fast` replay takes exactly the same decisions as the live run.
//
// Rules (docs/daemon.md, "Faults"):
//   - A pose stamped more than max_gap before the last pose: the camera clock jumped back.
//   - A control stamped more than max_gap before the newest control: the control clock
//     jumped back. The control is held (with the ones behind it) until the poses show the
//     jump too, so that every pose of the old base is used first; the caller starts the new
//     base from the held control if they do not (the poses end, or live, a second passes).
//   - After a jump, events of the other stream still stamped on the old base (later than
//     the jump's time by more than max_gap) are discarded until that stream shows a stamp
//     on the new base.
#pragma once

#include <limits>
#include <optional>

#include "kincal/online/samples.h"
#include "kincal/time.h"

namespace kincal {

class TimeBase {
 public:
  enum class Stream { kControls, kPoses };
  // "Never": a time before any other, with room for differences without overflow.
  static constexpr TimeNs kNever = std::numeric_limits<TimeNs>::min() / 4;

  explicit TimeBase(TimeNs max_gap_ns) : max_gap_ns_(max_gap_ns) {}

  // True if an event of `stream` at t is still on a base that was just left (discard it).
  // The first event on the new base ends the discarding for its stream.
  bool FromOldBase(TimeNs t, Stream stream);
  // The control clock jumped back at t (the control must be held).
  bool IsControlJump(TimeNs t) const {
    return max_control_ns_ != kNever && t < max_control_ns_ - max_gap_ns_;
  }
  // The camera clock jumped back at t.
  bool IsPoseJump(TimeNs t) const {
    return last_pose_ns_ != kNever && t < last_pose_ns_ - max_gap_ns_;
  }
  // Starts a new base at t, seen in `by`: the last pose and newest control are forgotten
  // and the other stream's old-base events are discarded from now on.
  void StartNew(TimeNs t, Stream by);

  // A control at t was used; a pose at t was taken (used or not).
  void ControlUsed(TimeNs t) { max_control_ns_ = std::max(max_control_ns_, t); }
  void PoseSeen(TimeNs t) { last_pose_ns_ = t; }

  // The held control of a control-clock jump, and since when (host monotonic ns).
  void Hold(const ControlSample& c, TimeNs since_mono_ns) {
    held_ = c;
    held_since_mono_ns_ = since_mono_ns;
  }
  bool holding() const { return held_.has_value(); }
  const ControlSample& held() const { return *held_; }
  TimeNs held_since_mono_ns() const { return held_since_mono_ns_; }
  // Releases the held control onto the new base (after StartNew): the controls have
  // rebased.
  ControlSample ReleaseHeld();

  bool has_controls() const { return max_control_ns_ != kNever; }
  bool has_poses() const { return last_pose_ns_ != kNever; }
  TimeNs newest_control_ns() const { return max_control_ns_; }
  TimeNs last_pose_ns() const { return last_pose_ns_; }
  // True while old-base events of a stream may still arrive.
  bool rebasing() const { return horizon_ns_ != kNever; }

 private:
  TimeNs max_gap_ns_;
  TimeNs max_control_ns_ = kNever;
  TimeNs last_pose_ns_ = kNever;
  TimeNs horizon_ns_ = kNever;  // kNever: no new base being established
  bool controls_rebased_ = true, poses_rebased_ = true;
  std::optional<ControlSample> held_;
  TimeNs held_since_mono_ns_ = 0;
};

}  // namespace kincal
