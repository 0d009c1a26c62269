// The whole daemon on the simulated camera: parameters within 3 sigma of the truth, record
// -> replay bit-identical, controls over LCM, published outputs, resume from a checkpoint,
// malformed log events rejected and counted.
#include "kincal/daemon/daemon.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/health_t.hpp>
#include <kincal/markers_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <kincal/preview_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <thread>

#include "daemon/daemon_test_util.h"
#include "kincal/daemon/config.h"
#include "kincal/io/checkpoint.h"
#include "kincal/sim/scenario.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

// The shipped simulated robot with health and model checks at 5 Hz.
DaemonConfig SimConfig5Hz(double duration_s) {
  DaemonConfig c = SimConfig(duration_s);
  c.health_rate_hz = 5;
  return c;
}

// Within 3 sigma, and converged: each sigma under 0.2 % of its value.
void ExpectConvergedWithin3Sigma(const Checkpoint& e, const std::map<std::string, double>& truth) {
  ASSERT_EQ(e.names.size(), 3u);
  ExpectWithin3Sigma(e, truth);
  for (size_t i = 0; i < e.names.size(); ++i) {
    const double sigma = std::sqrt(e.covariance(static_cast<int>(i), static_cast<int>(i)));
    EXPECT_LT(sigma, 0.002 * std::abs(truth.at(e.names[i]))) << e.names[i] << ": not converged";
  }
}

TEST(DaemonSim, ConvergesToTheSimulatedRobotAndReplaysBitIdentically) {
  DaemonConfig c = SimConfig5Hz(40);
  c.record.path = TempPath("sim.lcm");
  Checkpoint live;
  DaemonCounters lc;
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
    live = d.Estimate();
    lc = d.counters();
  }
  // The guess starts 5-10 % off; 40 s of simulated driving pins the parameters down.
  ExpectConvergedWithin3Sigma(live, Truth(c));
  EXPECT_GT(lc.updates, 1000);
  EXPECT_EQ(lc.frames_dropped_queue, 0);
  EXPECT_EQ(lc.log_events_lost, 0);
  EXPECT_EQ(lc.messages_rejected, 0);
  // Replay the log twice, as fast as possible: the same estimate, bit for bit, both times
  // and as the live (lossless) run.
  std::vector<Checkpoint> replays;
  for (int k = 0; k < 2; ++k) {
    DaemonConfig r = c;
    r.source = SourceKind::kReplay;
    r.replay.path = c.record.path;
    r.replay.speed = 0;
    r.record.path.clear();
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(r).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
    replays.push_back(d.Estimate());
    EXPECT_EQ(d.counters().frames_captured, lc.frames_captured);
  }
  for (const auto& r : replays) {
    EXPECT_EQ(r.values, live.values);
    EXPECT_EQ(r.covariance, live.covariance);
    EXPECT_EQ(r.update_count, live.update_count);
  }
}

TEST(DaemonSim, ControlsOverLcmAndPublishedOutputs) {
  DaemonConfig c = SimConfig5Hz(20);
  c.sim.controls_via_lcm = true;  // the filter gets the robot's controls only through LCM
  c.sim.speed = 4;                // paced: LCM delivery keeps up
  c.robot.control_stamp = ControlStamp::kReceive;
  std::string error;
  EXPECT_FALSE(c.IsValid(&error)) << "wall-clock receive stamps on a 4x simulation";
  c.robot.control_stamp = ControlStamp::kMapped;
  EXPECT_FALSE(c.IsValid(&error)) << "a 4x clock does not map onto the wall clock";
  c.robot.control_stamp = ControlStamp::kSender;
  c.record.path = TempPath("sim_lcm.lcm");
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
  Daemon& d = *d_owner;
  ASSERT_EQ(d.Run(), 0);
  const DaemonCounters k = d.counters();
  ExpectConvergedWithin3Sigma(d.Estimate(), Truth(c));
  EXPECT_GT(k.controls_received, 900);  // 50 Hz for 20 s
  EXPECT_GT(k.updates, 400);
  // The log holds every output, readable as a kincal recording.
  lcm::LogFile log(c.record.path, "r");
  std::map<std::string, int> per_channel;
  kincal::params_t last;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    ++per_channel[ev->channel];
    if (ev->channel == c.lcm.params_channel) {
      ASSERT_GT(last.decode(ev->data, 0, ev->datalen), 0);
    }
  }
  for (const auto* ch :
       {&c.lcm.frame_channel, &c.lcm.controls_channel, &c.lcm.pose_channel, &c.lcm.params_channel,
        &c.lcm.health_channel, &c.lcm.model_check_channel, &c.lcm.markers_channel}) {
    EXPECT_GT(per_channel[*ch], 0) << *ch;
  }
  EXPECT_EQ(per_channel[c.lcm.frame_channel], k.frames_captured);
  EXPECT_EQ(last.num_params, 3);
  EXPECT_EQ(last.values, d.Estimate().values);
}

TEST(DaemonSim, ResumesFromItsCheckpoint) {
  DaemonConfig c = SimConfig5Hz(15);
  c.checkpoint.path = TempPath("resume.json");
  Checkpoint first;
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
    first = d.Estimate();
  }
  ASSERT_TRUE(std::filesystem::exists(c.checkpoint.path));
  const Checkpoint saved = ReadCheckpoint(c.checkpoint.path).value();
  EXPECT_EQ(saved.values, first.values);
  // A second session starting from the checkpoint begins where the first ended: its
  // estimate is at least as tight, and closer than the configured (10 % off) guess.
  DaemonConfig c2 = c;
  c2.checkpoint.resume = c.checkpoint.path;
  c2.checkpoint.path.clear();
  const std::unique_ptr<Daemon> d2_owner = Daemon::Create(c2).value();
  Daemon& d2 = *d2_owner;
  ASSERT_EQ(d2.Run(), 0);
  const Checkpoint second = d2.Estimate();
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(second.covariance(i, i), first.covariance(i, i))
        << second.names[static_cast<size_t>(i)];
  }
  ExpectConvergedWithin3Sigma(second, Truth(c));
  c2.checkpoint.resume = TempPath("missing.json");
  const StatusOr<std::unique_ptr<Daemon>> d3 = Daemon::Create(c2);
  ASSERT_FALSE(d3.ok()) << "a missing checkpoint is an error, not a silent fresh start";
  EXPECT_NE(d3.status().message().find("missing.json"), std::string::npos) << d3.status().message();
}

// Reproduces a robot.fixed run whose checkpoint could be neither resumed nor exported:
// "variance of 'd' (0) is not plausible". A held parameter is written as held (zero
// variance, listed in `held`), read back, resumed held or, when this run frees it, with
// this run's prior spread; the free parameters carry on.
TEST(DaemonSim, ResumesAndExportsACheckpointWithAHeldParameter) {
  DaemonConfig c = SimConfig5Hz(40);  // a batch at 30 s and one at shutdown
  const auto truth = Truth(c);
  c.robot.fixed = {{"d", truth.at("d")}};
  c.checkpoint.path = TempPath("held.json");
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
  }
  StatusOr<Checkpoint> saved = ReadCheckpoint(c.checkpoint.path);
  ASSERT_TRUE(saved.ok()) << saved.status().message();
  EXPECT_EQ(saved->source, "batch");
  EXPECT_EQ(saved->held, std::vector<std::string>{"d"});
  EXPECT_EQ(saved->values[2], truth.at("d"));
  std::ostringstream yaml;
  WriteExportYaml(yaml, *saved, c.checkpoint.path);
  EXPECT_NE(yaml.str().find("held: true"), std::string::npos) << yaml.str();
  for (const bool still_held : {true, false}) {
    DaemonConfig c2 = c;
    c2.sim.duration_s = 15;
    c2.checkpoint.resume = c.checkpoint.path;
    c2.checkpoint.path.clear();
    if (!still_held) c2.robot.fixed.clear();
    const std::unique_ptr<Daemon> d2_owner = Daemon::Create(c2).value();
    Daemon& d2 = *d2_owner;
    ASSERT_EQ(d2.Run(), 0) << "held " << still_held;
    const Checkpoint e = d2.Estimate();
    ASSERT_EQ(e.names.size(), 3u);
    if (still_held) {  // fused with the first run's: the radii at least as tight
      for (int i = 0; i < 2; ++i) EXPECT_LE(e.covariance(i, i), saved->covariance(i, i));
      EXPECT_EQ(e.values[2], truth.at("d"));
      EXPECT_EQ(e.held, std::vector<std::string>{"d"});
    } else {
      EXPECT_TRUE(e.held.empty());
      EXPECT_GT(e.covariance(2, 2), 0.0);
    }
    ExpectWithin3Sigma(e, truth);
  }
}

// preview.enabled: the camera's picture at preview.rate_hz on LCM and in the log, each
// naming the frame whose markers it shows.
TEST(DaemonSim, PublishesAndRecordsThePreview) {
  DaemonConfig c = SimConfig5Hz(6);
  c.preview.enabled = true;
  c.record.path = TempPath("preview.lcm");
  DaemonCounters counted;
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
    counted = d.counters();
  }
  lcm::LogFile log(c.record.path, "r");
  std::vector<kincal::preview_t> previews;
  std::set<int64_t> marker_frames;
  std::map<int64_t, kincal::markers_t> markers;
  kincal::health_t last_health{};
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == c.lcm.health_channel) {
      ASSERT_EQ(last_health.decode(ev->data, 0, ev->datalen), ev->datalen);
    } else if (ev->channel == c.lcm.preview_channel) {
      kincal::preview_t m;
      ASSERT_EQ(m.decode(ev->data, 0, ev->datalen), ev->datalen);
      previews.push_back(m);
    } else if (ev->channel == c.lcm.markers_channel) {
      kincal::markers_t m;
      ASSERT_EQ(m.decode(ev->data, 0, ev->datalen), ev->datalen);
      marker_frames.insert(m.frame_sequence);
      markers[m.frame_sequence] = m;
    }
  }
  // 6 s at 5 Hz (the simulated camera's 30 Hz stamps: every sixth frame).
  EXPECT_NEAR(static_cast<double>(previews.size()), 30.0, 1.0);
  // Counted in health (issue 35): every preview published, none skipped (lossless: the
  // preview waits for its worker), the last health_t after the last preview.
  EXPECT_EQ(counted.preview_published, static_cast<int64_t>(previews.size()));
  EXPECT_EQ(counted.preview_skipped, 0);
  EXPECT_EQ(last_health.preview_published, static_cast<int64_t>(previews.size()));
  EXPECT_EQ(last_health.preview_skipped, 0);
  for (const auto& p : previews) {
    EXPECT_EQ(p.scale, 2);  // the default 640x480 camera, preview.width 320
    EXPECT_EQ(p.width, 320);
    EXPECT_EQ(p.height, 240);
    EXPECT_EQ(p.format, "jpeg");
    EXPECT_EQ(marker_frames.count(p.frame_sequence), 1u) << p.frame_sequence;
    EXPECT_FALSE(cv::imdecode(p.data, cv::IMREAD_GRAYSCALE).empty());
  }
  // The floor the camera sees, on the target's plane: the default camera (640 px across at
  // f = 500 px) 2 m above the floor, the markers 0.10 m up.
  ASSERT_FALSE(previews.empty());
  const auto& f = previews.front();
  ASSERT_EQ(f.num_floor, 32);
  const auto [x_min, x_max] = std::minmax_element(f.floor_x.begin(), f.floor_x.end());
  EXPECT_NEAR(*x_max - *x_min, 640.0 / 500.0 * (2.0 - 0.10), 1e-6);
  // The target's axes, projected from each frame's pose: the origin among the markers the
  // detector identified in that frame, each axis 0.1 m long = 500 / 1.9 px per m.
  int with_axes = 0;
  for (const auto& p : previews) {
    const kincal::markers_t& m = markers[p.frame_sequence];
    std::vector<double> us, vs;
    for (int i = 0; i < m.num_markers; ++i) {
      if (m.id[static_cast<size_t>(i)] < 0) continue;
      us.push_back(m.u[static_cast<size_t>(i)]);
      vs.push_back(m.v[static_cast<size_t>(i)]);
    }
    if (p.num_axes != 3 || us.size() < 3) continue;
    ++with_axes;
    EXPECT_GE(p.axes_u[0], *std::min_element(us.begin(), us.end()));
    EXPECT_LE(p.axes_u[0], *std::max_element(us.begin(), us.end()));
    EXPECT_GE(p.axes_v[0], *std::min_element(vs.begin(), vs.end()));
    EXPECT_LE(p.axes_v[0], *std::max_element(vs.begin(), vs.end()));
    for (int k = 1; k < 3; ++k) {
      EXPECT_NEAR(std::hypot(p.axes_u[static_cast<size_t>(k)] - p.axes_u[0],
                             p.axes_v[static_cast<size_t>(k)] - p.axes_v[0]),
                  0.1 * 500.0 / 1.9, 1e-6);
    }
  }
  EXPECT_GE(with_axes, static_cast<int>(previews.size()) * 8 / 10);
}

// Reproduces issue 16 (items 5 and 7): two daemons recording to one path both exited 0 and
// the first recording was lost; an unwritable checkpoint folder only showed as logged errors
// and exit 0.
TEST(DaemonOutputs, ASecondDaemonOnTheSameOutputIsRefusedNamingTheFirst) {
  DaemonConfig c = SimConfig5Hz(2);
  c.record.path = TempPath("shared.lcm");
  c.checkpoint.path = TempPath("shared.json");
  const std::unique_ptr<Daemon> first_owner = Daemon::Create(c).value();
  Daemon& first = *first_owner;
  const std::string pid = "(pid " + std::to_string(::getpid());
  const StatusOr<std::unique_ptr<Daemon>> refused1 = Daemon::Create(c);
  ASSERT_FALSE(refused1.ok()) << "a second daemon recording to the same path was accepted";
  EXPECT_NE(refused1.status().message().find(
                "shared.lcm: the recording is in use by another process " + pid),
            std::string::npos)
      << refused1.status().message();
  DaemonConfig ck_only = c;
  ck_only.record.path = TempPath("other.lcm");
  const StatusOr<std::unique_ptr<Daemon>> refused2 = Daemon::Create(ck_only);
  ASSERT_FALSE(refused2.ok()) << "a second daemon writing the same checkpoint was accepted";
  EXPECT_NE(refused2.status().message().find("shared.json: the checkpoint is in use"),
            std::string::npos)
      << refused2.status().message();
  EXPECT_EQ(first.Run(), 0);
}

TEST(DaemonOutputs, AnUnwritableCheckpointFolderFailsAtStart) {
  DaemonConfig c = SimConfig5Hz(2);
  c.checkpoint.path = TempPath("no_such_folder") + "/ck.json";
  const StatusOr<std::unique_ptr<Daemon>> refused3 = Daemon::Create(c);
  ASSERT_FALSE(refused3.ok()) << "started with a checkpoint it cannot write";
  EXPECT_NE(refused3.status().message().find("No such file or directory"), std::string::npos)
      << refused3.status().message();
}

// The log of a run without its frames: controls and poses only, as `kincal import` writes
// motion capture (with `zero_covariance`, as a PoseStamped has none).
void StripFrames(const std::string& in_path, const std::string& out_path, bool zero_covariance) {
  lcm::LogFile in(in_path, "r");
  lcm::LogFile out(out_path, "w");
  while (const lcm::LogEvent* ev = in.readNextEvent()) {
    const std::string ch = ev->channel;
    if (ch != "KINCAL_CONTROLS" && ch != "KINCAL_POSE") continue;
    kincal::pose_t p;
    std::vector<uint8_t> bytes(static_cast<const uint8_t*>(ev->data),
                               static_cast<const uint8_t*>(ev->data) + ev->datalen);
    if (ch == "KINCAL_POSE" && zero_covariance) {
      ASSERT_GT(p.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
      std::fill(std::begin(p.covariance), std::end(p.covariance), 0.0);
      p.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    }
    lcm::LogEvent copy = *ev;
    copy.data = bytes.data();
    out.writeEvent(&copy);
  }
}

TEST(DaemonReplay, ALogWithoutFramesCalibratesFromItsPoses) {
  DaemonConfig c = SimConfig5Hz(20);
  c.record.path = TempPath("with_frames.lcm");
  Checkpoint live;
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    ASSERT_EQ(d_owner->Run(), 0);
    live = d_owner->Estimate();
  }
  for (const bool zero : {false, true}) {
    SCOPED_TRACE(zero ? "poses without covariance" : "poses with the pose stage's covariance");
    DaemonConfig r = c;
    r.source = SourceKind::kReplay;
    r.replay.path = TempPath(zero ? "mocap_zero.lcm" : "mocap.lcm");
    r.replay.speed = 0;
    r.record.path = TempPath("mocap_replayed.lcm");
    StripFrames(c.record.path, r.replay.path, zero);
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(r).value();
    ASSERT_EQ(d_owner->Run(), 0);
    const Checkpoint e = d_owner->Estimate();
    const DaemonCounters k = d_owner->counters();
    EXPECT_EQ(k.frames_captured, 0);
    EXPECT_GT(k.poses_valid, 300);
    EXPECT_EQ(k.poses_published, k.poses_valid + k.poses_invalid);
    ExpectWithin3Sigma(e, Truth(c));
    if (!zero) {
      // The poses and covariances the live filter had: the same calibration.
      for (size_t i = 0; i < e.values.size(); ++i) {
        EXPECT_NEAR(e.values[i], live.values[i], 1e-9 * std::abs(live.values[i])) << e.names[i];
      }
    }
  }
}

TEST(DaemonReplay, MalformedEventsAreRejectedAndCounted) {
  // A log with a valid simulated run plus hostile events on the controls and frame
  // channels: undecodable bytes, the wrong model, NaN, a huge declared array, a frame
  // whose declared size disagrees with its data.
  DaemonConfig c = SimConfig5Hz(8);
  c.record.path = TempPath("clean.lcm");
  Checkpoint clean;
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
    clean = d.Estimate();
  }
  const std::string hostile = TempPath("hostile.lcm");
  {
    lcm::LogFile in(c.record.path, "r");
    lcm::LogFile out(hostile, "w");
    int n = 0;
    auto write = [&](const std::string& ch, int64_t t, const std::vector<uint8_t>& bytes) {
      lcm::LogEvent ev{};
      ev.timestamp = t;
      ev.channel = ch;
      ev.datalen = static_cast<int32_t>(bytes.size());
      ev.data = const_cast<uint8_t*>(bytes.data());
      out.writeEvent(&ev);
    };
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      lcm::LogEvent copy = *ev;
      out.writeEvent(&copy);
      if (++n == 500) {
        const int64_t t = ev->timestamp;
        write(c.lcm.controls_channel, t, {1, 2, 3});
        kincal::controls_t m;
        m.schema_version = 1;
        m.utime = t;
        m.model = "tricycle";
        m.num_controls = 2;
        m.names = {"omega_l", "omega_r"};
        m.values = {1.0, 1.0};
        std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
        m.encode(buf.data(), 0, static_cast<int>(buf.size()));
        write(c.lcm.controls_channel, t, buf);
        m.model = "diffdrive";
        m.values = {std::nan(""), 1.0};
        buf.resize(static_cast<size_t>(m.getEncodedSize()));
        m.encode(buf.data(), 0, static_cast<int>(buf.size()));
        write(c.lcm.controls_channel, t, buf);
        // A valid header declaring 2^31-1 controls, then the data ends. Layout: hash (8),
        // schema_version (4), utime (8), sender_utime (8), model (4 + "diffdrive\0").
        ASSERT_GT(buf.size(), 42u);
        std::vector<uint8_t> huge(buf.begin(), buf.begin() + 42);
        for (const uint8_t b : {0x7f, 0xff, 0xff, 0xff}) huge.push_back(b);
        write(c.lcm.controls_channel, t, huge);
        write(c.lcm.frame_channel, t, std::vector<uint8_t>(100, 0xab));
      }
    }
  }
  // And the log ends with an event cut short (a header without its body).
  std::ofstream(hostile, std::ios::app | std::ios::binary)
      << std::string("\xed\xa1\xda\x01\0\0\0\0", 8);
  DaemonConfig r = c;
  r.source = SourceKind::kReplay;
  r.replay.path = hostile;
  r.replay.speed = 0;
  r.record.path.clear();
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(r).value();
  Daemon& d = *d_owner;
  ASSERT_EQ(d.Run(), 0);
  EXPECT_EQ(d.counters().messages_rejected, 4);
  EXPECT_EQ(d.counters().frames_bad, 2);  // the corrupt frame and the cut-short end
  EXPECT_EQ(d.Estimate().values, clean.values) << "rejected input must not change the estimate";
}

}  // namespace
}  // namespace kincal::daemon
