// TimeBase: the rules that decide which poses and controls belong to the filter's time
// base, checked event by event against what docs/daemon.md states.
#include "kincal/online/time_base.h"

#include <gtest/gtest.h>

namespace kincal {
namespace {

const TimeNs kGap = SecondsToNs(0.5);
constexpr TimeNs S(double s) { return static_cast<TimeNs>(s * 1e9); }

ControlSample TimeBaseControlAt(TimeNs t) {
  ControlSample c;
  c.utime = PipelineNsToUtime(t);
  return c;
}

TEST(TimeBase, StartsEmptyAndTracksTheNewestControlAndLastPose) {
  TimeBase tb(kGap);
  EXPECT_FALSE(tb.has_controls());
  EXPECT_FALSE(tb.has_poses());
  EXPECT_FALSE(tb.IsControlJump(S(100)));
  EXPECT_FALSE(tb.IsPoseJump(S(100)));
  tb.ControlUsed(S(10));
  tb.ControlUsed(S(9));  // an older control does not move the newest back
  EXPECT_EQ(tb.newest_control_ns(), S(10));
  tb.PoseSeen(S(10.2));
  EXPECT_EQ(tb.last_pose_ns(), S(10.2));
}

TEST(TimeBase, AJumpIsMoreThanTheGapBackNotLess) {
  TimeBase tb(kGap);
  tb.ControlUsed(S(10));
  tb.PoseSeen(S(10));
  // Exactly the gap back, or a little less: reordering, not a jump.
  EXPECT_FALSE(tb.IsControlJump(S(9.5)));
  EXPECT_FALSE(tb.IsPoseJump(S(9.6)));
  // More than the gap back: the clock jumped.
  EXPECT_TRUE(tb.IsControlJump(S(9.5) - 1));
  EXPECT_TRUE(tb.IsPoseJump(S(2)));
}

TEST(TimeBase, CameraJumpDiscardsOldBaseControlsUntilTheControlsShowTheJump) {
  TimeBase tb(kGap);
  tb.ControlUsed(S(100));
  tb.PoseSeen(S(100));
  // The camera clock jumps back to 5 s: a new base at 5 s.
  tb.StartNew(S(5), TimeBase::Stream::kPoses);
  EXPECT_FALSE(tb.has_controls());
  EXPECT_FALSE(tb.has_poses());
  EXPECT_TRUE(tb.rebasing());
  // Poses are already on the new base.
  EXPECT_FALSE(tb.FromOldBase(S(5.1), TimeBase::Stream::kPoses));
  // Controls still stamped near 100 s are on the old base: discarded.
  EXPECT_TRUE(tb.FromOldBase(S(100.1), TimeBase::Stream::kControls));
  EXPECT_TRUE(tb.FromOldBase(S(5.6), TimeBase::Stream::kControls));  // beyond 5 s + gap
  // The first control within the gap of the jump rebases the controls: done.
  EXPECT_FALSE(tb.FromOldBase(S(5.2), TimeBase::Stream::kControls));
  EXPECT_FALSE(tb.rebasing());
  // From then on nothing is discarded, whatever its time.
  EXPECT_FALSE(tb.FromOldBase(S(100.2), TimeBase::Stream::kControls));
}

TEST(TimeBase, HeldControlJumpIsReleasedOntoTheNewBase) {
  TimeBase tb(kGap);
  tb.ControlUsed(S(50));
  tb.PoseSeen(S(50));
  ASSERT_TRUE(tb.IsControlJump(S(1)));
  tb.Hold(TimeBaseControlAt(S(1)), /*since_mono_ns=*/777);
  EXPECT_TRUE(tb.holding());
  EXPECT_EQ(tb.held_since_mono_ns(), 777);
  // The poses show the jump: a new base from the poses, then the held control joins it.
  tb.StartNew(S(1.1), TimeBase::Stream::kPoses);
  const ControlSample c = tb.ReleaseHeld();
  EXPECT_EQ(c.utime, PipelineNsToUtime(S(1)));
  EXPECT_FALSE(tb.holding());
  // Both streams are on the new base: nothing more is discarded.
  EXPECT_FALSE(tb.rebasing());
  EXPECT_FALSE(tb.FromOldBase(S(60), TimeBase::Stream::kControls));
  EXPECT_FALSE(tb.FromOldBase(S(60), TimeBase::Stream::kPoses));
}

TEST(TimeBase, ControlsAloneStartTheNewBaseAndOldPosesAreDiscarded) {
  TimeBase tb(kGap);
  tb.ControlUsed(S(50));
  tb.PoseSeen(S(50));
  tb.Hold(TimeBaseControlAt(S(1)), 0);
  // The poses did not follow (the stream ended, or a second passed live).
  tb.StartNew(S(1), TimeBase::Stream::kControls);
  tb.ReleaseHeld();
  EXPECT_TRUE(tb.rebasing());  // the poses have not shown the new base yet
  EXPECT_TRUE(tb.FromOldBase(S(50.1), TimeBase::Stream::kPoses));
  EXPECT_FALSE(tb.FromOldBase(S(1.3), TimeBase::Stream::kPoses));
  EXPECT_FALSE(tb.rebasing());
}

// --fast determinism: the decisions depend on the stamps alone, so the same sequence of
// events gives the same decisions however the calls are timed.
TEST(TimeBase, DecisionsDependOnStampsOnly) {
  auto run = [](TimeNs mono) {
    TimeBase tb(kGap);
    std::vector<int> decisions;
    const TimeNs events[] = {S(1), S(2), S(3), S(0.5), S(3.2), S(0.7), S(0.9)};
    for (TimeNs t : events) {
      if (tb.FromOldBase(t, TimeBase::Stream::kControls)) {
        decisions.push_back(0);
      } else if (tb.IsControlJump(t)) {
        tb.Hold(TimeBaseControlAt(t), mono);
        tb.StartNew(t, TimeBase::Stream::kControls);
        tb.ControlUsed(UtimeToPipelineNs(tb.ReleaseHeld().utime));
        decisions.push_back(1);
      } else {
        tb.ControlUsed(t);
        decisions.push_back(2);
      }
    }
    return decisions;
  };
  EXPECT_EQ(run(0), run(123456789));
  // 0.5 s: more than the gap behind 3 s, a jump; 3.2 s is then on the new base, and 0.7 s
  // is a second jump behind it.
  EXPECT_EQ(run(0), (std::vector<int>{2, 2, 2, 1, 2, 1, 2}));
}

}  // namespace
}  // namespace kincal
