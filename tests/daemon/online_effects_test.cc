// OnlineEffects: when a search starts (a suspect, enough data, after the cooldown), and
// when its result applies (lossless: at a fixed data time after the start, so that a
// replay decides the same every time); a fruitless search doubles the wait.
#include "daemon/online_effects.h"

#include <gtest/gtest.h>

#include "analysis/analysis_test_util.h"

namespace kincal::daemon {
namespace {

// Controls and poses of a recording fed as the filter stage would, up to t_s.
struct Fed {
  Recording rec;
  PoseRing ring{4096};
  size_t next_control = 0, next_pose = 0;
  void Until(OnlineEffects* online, double t_s) {
    const TimeNs t = SecondsToNs(t_s);
    for (; next_control < rec.controls.size(); ++next_control) {
      const TimeNs tc = rec.controls.ToNs(rec.controls.TimeAt(static_cast<int>(next_control)));
      if (tc > t) break;
      const auto& v = rec.controls.ValuesAt(static_cast<int>(next_control));
      online->AddControl(tc, std::span<const double>(v.data(), 2), 2);
    }
    for (; next_pose < rec.poses.size() && rec.poses[next_pose].t_ns <= t; ++next_pose) {
      PoseSample p;
      p.utime = rec.poses[next_pose].t_ns / 1000;
      p.valid = true;
      p.xytheta = rec.poses[next_pose].z;
      if (ring.full()) ring.pop();
      ring.push(p);
    }
  }
};

ModelCheckVerdict Suspect(const std::string& name) {
  ModelCheckVerdict v;
  v.suspected_effect = name;
  v.candidates = {name};
  return v;
}

OnlineEffectsOptions Lossless() {
  OnlineEffectsOptions o;
  o.enabled = true;
  o.lossless = true;
  return o;
}

TEST(OnlineEffects, SearchesOnlyWithASuspectAndEnoughData) {
  OnlineEffects online(Lossless());
  Fed fed{testing::UnicycleRecording(80.0, {"time_offset"}, {{"delay_s", 0.2}}, 6)};
  const System sys = MakeSystem("unicycle");
  VecN<kMaxState> p(2);
  p << 0.9, 0.8;
  fed.Until(&online, 20.0);
  online.OnCheck(SecondsToNs(20.0), Suspect("time_offset"), fed.ring, sys, p, {});
  EXPECT_FALSE(online.searching());  // 20 s < min_window_s
  fed.Until(&online, 40.0);
  online.OnCheck(SecondsToNs(40.0), ModelCheckVerdict{}, fed.ring, sys, p, {});
  EXPECT_FALSE(online.searching());  // no suspect
  online.OnCheck(SecondsToNs(40.0), Suspect("time_offset"), fed.ring, sys, p, {});
  ASSERT_TRUE(online.searching());
  // Lossless: nothing before apply_after_s of data time, then the result, whole.
  EXPECT_FALSE(online.OnPose(SecondsToNs(44.9)).has_value());
  const auto r = online.OnPose(SecondsToNs(45.0));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->added, std::vector<std::string>{"time_offset"}) << r->evidence;
  EXPECT_FALSE(online.searching());
  // The cooldown holds the next search off.
  fed.Until(&online, 50.0);
  online.OnCheck(SecondsToNs(50.0), Suspect("actuator_lag"), fed.ring, sys, p, {"time_offset"});
  EXPECT_FALSE(online.searching());
  EXPECT_EQ(online.searches(), 1);
}

TEST(OnlineEffects, AFruitlessSearchDoublesTheWait) {
  OnlineEffectsOptions o = Lossless();
  o.cooldown_s = 10.0;
  OnlineEffects online(o);
  Fed fed{testing::UnicycleRecording(120.0, {}, {}, 7)};
  const System sys = MakeSystem("unicycle");
  VecN<kMaxState> p(2);
  p << 0.9, 0.8;
  fed.Until(&online, 40.0);
  online.OnCheck(SecondsToNs(40.0), Suspect("lever_arm"), fed.ring, sys, p, {});
  ASSERT_TRUE(online.searching());
  EXPECT_FALSE(online.OnPose(SecondsToNs(45.0)).has_value());  // clean: nothing added
  EXPECT_FALSE(online.searching());
  fed.Until(&online, 54.0);
  online.OnCheck(SecondsToNs(54.0), Suspect("lever_arm"), fed.ring, sys, p, {});
  EXPECT_FALSE(online.searching());  // within 10 s of the fruitless result
  fed.Until(&online, 56.0);
  online.OnCheck(SecondsToNs(56.0), Suspect("lever_arm"), fed.ring, sys, p, {});
  ASSERT_TRUE(online.searching());
  EXPECT_FALSE(online.OnPose(SecondsToNs(61.0)).has_value());
  fed.Until(&online, 75.0);
  online.OnCheck(SecondsToNs(75.0), Suspect("lever_arm"), fed.ring, sys, p, {});
  EXPECT_FALSE(online.searching());  // now 20 s
  fed.Until(&online, 82.0);
  online.OnCheck(SecondsToNs(82.0), Suspect("lever_arm"), fed.ring, sys, p, {});
  EXPECT_TRUE(online.searching());
  online.Reset();
  EXPECT_FALSE(online.searching());
}

}  // namespace
}  // namespace kincal::daemon
