#include "daemon/pose_control_merge.h"

#include "daemon/pose_ring.h"
#include "daemon/sources.h"

namespace kincal::daemon {
namespace {

// The filter thread waits this long for a pose, then looks at the controls again.
constexpr auto kPoseWait = std::chrono::milliseconds(20);
// A control clock jump is held this long (live) for the poses to show it too.
constexpr TimeNs kHeldJumpWaitNs = kNsPerSecond;

}  // namespace

void RunPoseControlMerge(FilterStage* stage_ptr, const MergeInputs& in) {
  FilterStage& stage = *stage_ptr;
  PoseRing pending(in.max_pending_poses);
  PoseSample p;
  while (true) {
    const bool got = in.poses->Pop(p, kPoseWait);
    stage.DrainControls(MonotonicNs());
    if (got) {
      if (pending.full()) {  // hold no more: use the oldest with what we have
        stage.AddPose(pending.front(), MonotonicNs());
        pending.pop();
      }
      pending.push(p);
    }
    const bool stopping = in.stop->load();
    const bool poses_over = !got && in.poses->closed_and_empty();
    const bool no_more_controls =
        in.controls_done->load() && in.controls->size() == 0 && !stage.holding_jump();
    if (no_more_controls) stage.DrainControls(MonotonicNs());
    // The controls jumped back and the poses did not follow: the controls alone start the
    // new time base (live after a while; lossless when the poses have ended).
    if (stage.holding_jump() && pending.empty() &&
        (poses_over ||
         (!in.lossless && MonotonicNs() - stage.held_since_mono_ns() > kHeldJumpWaitNs))) {
      stage.TakeControlJump(MonotonicNs());
    }
    while (!pending.empty()) {
      const PoseSample& f = pending.front();
      const bool waited =
          !in.lossless && MonotonicNs() - f.arrival_mono_ns > in.max_control_delay_ns;
      if (!(stage.ControlsCover(f) || no_more_controls || (poses_over && stopping) || waited)) {
        break;
      }
      stage.AddPose(f, MonotonicNs());
      pending.pop();
    }
    if (poses_over && (no_more_controls || stopping || !in.lossless)) {
      stage.DrainControls(MonotonicNs());
      for (; !pending.empty(); pending.pop()) stage.AddPose(pending.front(), MonotonicNs());
      break;
    }
  }
  stage.Finish();
}

}  // namespace kincal::daemon
