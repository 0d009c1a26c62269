#include "daemon/pose_control_merge.h"

#include "daemon/sources.h"
#include "kincal/online/pose_ring.h"

namespace kincal::daemon {
namespace {

// The filter thread waits this long for a pose, then looks at the controls again.
constexpr auto kPoseWait = std::chrono::milliseconds(20);
// A control clock jump is held this long (live) for the poses to show it too.
constexpr TimeNs kHeldJumpWaitNs = kNsPerSecond;

// What one pass of the merge knows about its inputs.
struct MergeState {
  bool stopping = false;
  bool poses_over = false;        // the pose queue is closed and empty
  bool no_more_controls = false;  // the controls ended and every one was used
};

// The controls jumped back and the poses did not follow: the controls alone start the new
// time base (live after a while; lossless when the poses have ended).
bool ControlsJumpAlone(const FilterStage& stage, const MergeInputs& in, const MergeState& s,
                       const PoseRing& pending) {
  return stage.holding_jump() && pending.empty() &&
         (s.poses_over ||
          (!in.lossless && MonotonicNs() - stage.held_since_mono_ns() > kHeldJumpWaitNs));
}

// Hands the held poses the controls now cover (or that waited long enough, or all of them
// at the end) to the filter, oldest first.
void ReleaseCovered(FilterStage* stage, const MergeInputs& in, const MergeState& s,
                    PoseRing* pending) {
  while (!pending->empty()) {
    const PoseSample& f = pending->front();
    const bool waited = !in.lossless && MonotonicNs() - f.arrival_mono_ns > in.max_control_delay_ns;
    if (!(stage->ControlsCover(f) || s.no_more_controls || (s.poses_over && s.stopping) ||
          waited)) {
      break;
    }
    stage->AddPose(f, MonotonicNs());
    pending->pop();
  }
}

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
    MergeState s;
    s.stopping = in.stop->load();
    s.poses_over = !got && in.poses->closed_and_empty();
    s.no_more_controls =
        in.controls_done->load() && in.controls->size() == 0 && !stage.holding_jump();
    if (s.no_more_controls) stage.DrainControls(MonotonicNs());
    if (ControlsJumpAlone(stage, in, s, pending)) stage.TakeControlJump(MonotonicNs());
    ReleaseCovered(&stage, in, s, &pending);
    if (s.poses_over && (s.no_more_controls || s.stopping || !in.lossless)) {
      stage.DrainControls(MonotonicNs());
      for (; !pending.empty(); pending.pop()) stage.AddPose(pending.front(), MonotonicNs());
      break;
    }
  }
  stage.Finish();
}

}  // namespace kincal::daemon
