#include "kincal/online/time_base.h"

#include <cassert>

namespace kincal {

bool TimeBase::FromOldBase(TimeNs t, Stream stream) {
  bool& rebased = stream == Stream::kControls ? controls_rebased_ : poses_rebased_;
  if (horizon_ns_ == kNever || rebased) return false;
  if (t > horizon_ns_) return true;
  rebased = true;
  if (controls_rebased_ && poses_rebased_) horizon_ns_ = kNever;
  return false;
}

void TimeBase::StartNew(TimeNs t, Stream by) {
  max_control_ns_ = kNever;
  last_pose_ns_ = kNever;
  horizon_ns_ = t + max_gap_ns_;
  controls_rebased_ = by == Stream::kControls;
  poses_rebased_ = by == Stream::kPoses;
}

ControlSample TimeBase::ReleaseHeld() {
  assert(held_.has_value());
  ControlSample c = *held_;
  held_.reset();
  controls_rebased_ = true;
  if (poses_rebased_) horizon_ns_ = kNever;
  return c;
}

}  // namespace kincal
