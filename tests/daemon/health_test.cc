// The health message: every counter published under its own name, and what changed in
// the period named in the message.
#include "daemon/health.h"

#include <gtest/gtest.h>

#include <kincal/params_t.hpp>

namespace kincal::daemon {
namespace {

TEST(Health, EveryCounterIsPublishedWhole) {
  DaemonCounters c;
  int64_t v = 1;
#define KINCAL_SET(name, meaning) c.name = v++;
  KINCAL_DAEMON_COUNTERS(KINCAL_SET)
#undef KINCAL_SET
  c.control_jitter_p95_ms = 12.5;
  c.control_jitter_max_ms = 80.0;
  HealthReporter r;
  kincal::health_t h;
  r.Build(c, HealthStatus{}, 1.0, 42, &h);
  EXPECT_EQ(h.schema_version, 8);
  EXPECT_EQ(h.control_jitter_p95_ms, 12.5);
  EXPECT_EQ(h.control_jitter_max_ms, 80.0);
  EXPECT_NE(h.message.find("the robot's clock stepped"), std::string::npos) << h.message;
  EXPECT_EQ(h.utime, 42);
  v = 1;
#define KINCAL_CHECK_FIELD(name, meaning) EXPECT_EQ(h.name, v++) << #name;
  KINCAL_DAEMON_COUNTERS(KINCAL_CHECK_FIELD)
#undef KINCAL_CHECK_FIELD
}

// Reproduces issue 16 (item 13): health said "bad frames: " with no reason when the source
// itself rejected what it read.
TEST(Health, BadFramesAlwaysSayWhy) {
  HealthReporter r;
  HealthStatus s;
  DaemonCounters c;
  kincal::health_t h;
  r.Build(c, s, 1.0, 1, &h);
  c.frames_bad = 3;
  r.Build(c, s, 1.0, 2, &h);
  EXPECT_NE(h.message.find("bad frames: 3 the source could not decode"), std::string::npos)
      << h.message;
  c.frames_bad = 4;
  s.last_frame_error = "MJPG frame: header declares 10x10, expected 640x480";
  r.Build(c, s, 1.0, 3, &h);
  EXPECT_NE(h.message.find("bad frames: MJPG frame: header declares"), std::string::npos)
      << h.message;
}

TEST(Health, QueueDropsAreNamedInThePeriodTheyHappen) {
  HealthReporter r;
  HealthStatus s;
  DaemonCounters c;
  c.frames_captured = 30;
  kincal::health_t h;
  r.Build(c, s, 1.0, 1, &h);
  EXPECT_EQ(h.ok, 1) << h.message;
  EXPECT_DOUBLE_EQ(h.frame_rate_hz, 30.0);
  c.frames_captured = 45;
  c.poses_dropped_queue = 3;
  c.controls_dropped_queue = 2;
  r.Build(c, s, 0.5, 2, &h);
  EXPECT_EQ(h.ok, 0);
  EXPECT_DOUBLE_EQ(h.frame_rate_hz, 30.0);
  EXPECT_NE(h.message.find("pose queue full"), std::string::npos) << h.message;
  EXPECT_NE(h.message.find("control queue full"), std::string::npos) << h.message;
  EXPECT_EQ(h.poses_dropped_queue, 3);
  // Nothing new in the next period: ok again, the totals stay.
  r.Build(c, s, 1.0, 3, &h);
  EXPECT_EQ(h.ok, 1) << h.message;
  EXPECT_EQ(h.controls_dropped_queue, 2);
}

TEST(Health, StandingConditionsAreReportedEveryTime) {
  HealthReporter r;
  HealthStatus s;
  s.since_last_frame_ns = 3 * kNsPerSecond;
  s.expects_lcm_controls = true;
  s.controls_channel = "ROBOT_CMD";
  s.source_error = "/dev/video0: VIDIOC_DQBUF: No such device";
  DaemonCounters c;
  c.frames_captured = 10;
  kincal::health_t h;
  for (int i = 0; i < 2; ++i) {
    r.Build(c, s, 1.0, i, &h);
    EXPECT_EQ(h.ok, 0);
    EXPECT_NE(h.message.find("no frames for 2 s"), std::string::npos) << h.message;
    EXPECT_NE(h.message.find("no controls received on ROBOT_CMD"), std::string::npos);
    EXPECT_NE(h.message.find("source: /dev/video0: VIDIOC_DQBUF: No such device"),
              std::string::npos);
  }
  s.source_done = true;  // a replay that ended: silence is expected
  s.source_error.clear();
  c.controls_received = 5;
  r.Build(c, s, 1.0, 3, &h);
  EXPECT_EQ(h.ok, 1) << h.message;
}

TEST(Health, NoTargetAndAModelThatDoesNotFitAreNotOk) {
  HealthReporter r;
  HealthStatus s;
  s.source_done = true;
  DaemonCounters c;
  c.frames_captured = 600;
  kincal::health_t h;
  s.seconds_without_target = 20.0;  // 600 frames, none with the target
  r.Build(c, s, 1.0, 1, &h);
  EXPECT_EQ(h.ok, 0);
  EXPECT_NE(h.message.find("no target seen for 20.0 s"), std::string::npos) << h.message;
  EXPECT_DOUBLE_EQ(h.seconds_without_target, 20.0);
  s.seconds_without_target = 1.0;
  s.filter_status = kincal::params_t::STATUS_MODEL_INADEQUATE;
  s.model_check_evidence = "heading innovation vs recent turn-command change (z = -9)";
  r.Build(c, s, 1.0, 2, &h);
  EXPECT_EQ(h.ok, 0);
  EXPECT_EQ(int{h.filter_status}, int{kincal::params_t::STATUS_MODEL_INADEQUATE});
  EXPECT_NE(h.message.find("the model does not fit the motion: heading innovation"),
            std::string::npos)
      << h.message;
  s.filter_status = kincal::params_t::STATUS_CONVERGED;
  r.Build(c, s, 1.0, 3, &h);
  EXPECT_EQ(h.ok, 1) << h.message;
}

// The account is logged when it changes and again every kRepeatNs while it stands; its
// clearing once ("health: ok"); nothing while all is well.
TEST(Health, AStandingAccountIsLoggedWhenItChangesAndAgainWhileItStands) {
  HealthReporter r;
  EXPECT_FALSE(r.Log("", 0));
  EXPECT_TRUE(r.Log("no frames for 3.0 s", 1));
  EXPECT_FALSE(r.Log("no frames for 3.0 s", 1 + HealthReporter::kRepeatNs));
  EXPECT_TRUE(r.Log("no frames for 3.0 s", 2 + HealthReporter::kRepeatNs));
  EXPECT_TRUE(r.Log("no frames for 4.0 s", 3 + HealthReporter::kRepeatNs));
  EXPECT_TRUE(r.Log("", 4 + HealthReporter::kRepeatNs));   // cleared: "health: ok"
  EXPECT_FALSE(r.Log("", 5 + HealthReporter::kRepeatNs));  // still well: nothing
  EXPECT_FALSE(r.Log("", 10 * HealthReporter::kRepeatNs));
}

}  // namespace
}  // namespace kincal::daemon

namespace kincal::daemon {
namespace {

// A replay with the wrong model's config rejected every control, never started the
// filter, wrote no checkpoint although --checkpoint asked for one, and exited 0.
TEST(Health, ALogThatEndsWithoutAnEstimateFails) {
  EndOfRun e;
  e.counters.poses_valid = 151;
  e.counters.messages_rejected = 251;
  e.last_reject = "controls for model 'diffdrive', expected 'unicycle'";
  e.checkpoint_path = "ck.json";
  EXPECT_EQ(EndOfRunError(e), "") << "stopped by a signal before the robot moved";
  EXPECT_EQ(EndOfRunCode(e), 0);
  e.source_ended = true;
  EXPECT_EQ(EndOfRunError(e),
            "the run ended without an estimate (ck.json not written): the filter never started "
            "(151 valid poses; 0 control messages accepted, 251 rejected, the last: controls for "
            "model 'diffdrive', expected 'unicycle')");
  EXPECT_EQ(EndOfRunCode(e), 1);
  e.checkpoint_path.clear();
  EXPECT_EQ(EndOfRunCode(e), 1) << "without --checkpoint too";
  e.counters.messages_rejected = 0;
  EXPECT_EQ(EndOfRunCode(e), 0) << "a log of frames alone gives poses (VmVimc's replay)";
  e.counters.messages_rejected = 251;
  e.has_estimate = true;
  EXPECT_EQ(EndOfRunCode(e), 0);
  e.checkpoint_error = "ck.json: checkpoint not written: the estimate is not finite";
  EXPECT_EQ(EndOfRunError(e), "the final checkpoint was not written: " + e.checkpoint_error);
  EXPECT_EQ(EndOfRunCode(e), 1);
  e.checkpoint_error.clear();
  e.source_error = "replay: truncated";
  EXPECT_EQ(EndOfRunCode(e), 1);
}

}  // namespace
}  // namespace kincal::daemon
