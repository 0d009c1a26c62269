// Reliability: timing faults, measurement faults, divergence, long runs. Each fault has a
// stated rule (docs/daemon.md, "Faults"), is counted, and leaves the estimate right.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/frame_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <random>
#include <set>

#include "daemon/daemon_test_util.h"
#include "kincal/daemon/config.h"
#include "kincal/daemon/daemon.h"
#include "kincal/estimation/online_calibrator.h"
#include "kincal/sim/scenario.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

struct Event {
  std::string channel;
  int64_t utime;
  std::vector<uint8_t> data;
};

std::vector<Event> ReadLog(const std::string& path) {
  lcm::LogFile log(path, "r");
  std::vector<Event> out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.push_back({ev->channel, ev->timestamp, std::vector<uint8_t>(p, p + ev->datalen)});
  }
  return out;
}

// Writes the events and checks that they read back whole (a full disk once cut a faulty
// log short, and the test then judged the daemon on part of it).
void WriteLog(const std::string& path, const std::vector<Event>& events) {
  {
    lcm::LogFile log(path, "w");
    for (const auto& e : events) {
      lcm::LogEvent ev{};
      ev.timestamp = e.utime;
      ev.channel = e.channel;
      ev.datalen = static_cast<int32_t>(e.data.size());
      ev.data = const_cast<uint8_t*>(e.data.data());
      ASSERT_EQ(log.writeEvent(&ev), 0) << path << ": cannot write an event";
    }
  }
  const std::vector<Event> back = ReadLog(path);
  ASSERT_EQ(back.size(), events.size()) << path << " was not written whole";
  EXPECT_EQ(back.back().data, events.back().data) << path << ": its last event differs";
}

template <typename Msg>
std::vector<uint8_t> Encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// Shifts every event from index `from` on by `dt_us`: event stamps and frame stamps.
void ShiftFrom(std::vector<Event>* events, size_t from, int64_t dt_us, const DaemonConfig& c) {
  for (size_t i = from; i < events->size(); ++i) {
    Event& e = (*events)[i];
    e.utime += dt_us;
    if (e.channel == c.lcm.frame_channel) {
      kincal::frame_t f;
      f.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      f.utime += dt_us;
      f.device_utime += dt_us;
      e.data = Encode(f);
    }
  }
}

// The replay's calibration; its filter's own final estimate into *filter when given.
Checkpoint Replay(const DaemonConfig& c, const std::string& log, DaemonCounters* counters,
                  Checkpoint* filter = nullptr) {
  DaemonConfig r = c;
  r.source = SourceKind::kReplay;
  r.replay.path = log;
  r.replay.speed = 0;
  r.record.path.clear();
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(r).value();
  Daemon& d = *d_owner;
  EXPECT_EQ(d.Run(), 0);
  *counters = d.counters();
  if (filter != nullptr) *filter = d.FilterEstimate();
  return d.Estimate();
}

TEST(TimingFaults, RepeatedEarlierAndJumpingStampsAndReorderedControlsFollowTheirRules) {
  DaemonConfig c = SimConfig(30);
  c.record.path = TempPath("clean.lcm");
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
  }
  std::vector<Event> events = ReadLog(c.record.path);
  // Frames whose pose was valid, and whose predecessor's was too (from the recorded
  // poses); where the clean run has its own gaps (the robot carried back).
  std::set<int64_t> valid;
  std::vector<size_t> natural_gaps;
  int64_t last_valid = 0;
  for (size_t i = 0; i < events.size(); ++i) {
    const auto& e = events[i];
    if (e.channel != c.lcm.pose_channel) continue;
    kincal::pose_t p;
    ASSERT_GT(p.decode(e.data.data(), 0, static_cast<int>(e.data.size())), 0);
    if (!p.valid) continue;
    valid.insert(p.utime);
    if (last_valid != 0 && p.utime - last_valid > 500'000) natural_gaps.push_back(i);
    last_valid = p.utime;
  }
  // Jumps and injected faults keep 300 events (about 2 s) away from each other and from
  // the natural gaps, so that each rule's count can be checked exactly.
  auto clear_of = [&](size_t i, const std::vector<size_t>& marks) {
    for (size_t m : marks) {
      if (i + 300 > m && i < m + 300) return false;
    }
    return true;
  };
  auto pick = [&](double lo, double hi) {
    for (size_t i = static_cast<size_t>(lo * static_cast<double>(events.size()));
         i < static_cast<size_t>(hi * static_cast<double>(events.size())); ++i) {
      if (clear_of(i, natural_gaps)) return i;
    }
    return events.size();
  };
  const size_t jump_forward_at = pick(0.25, 0.45), jump_back_at = pick(0.55, 0.8);
  ASSERT_LT(jump_back_at, events.size()) << "no stretch clear of natural gaps";
  std::vector<size_t> marks = natural_gaps;
  marks.push_back(jump_forward_at);
  marks.push_back(jump_back_at);
  std::vector<Event> faulty;
  int repeated = 0, earlier = 0, swapped = 0, frame_no = 0, control_no = 0;
  int64_t prev_frame_utime = 0;
  std::optional<Event> held;  // a control held back until the next one has gone out
  for (size_t i = 0; i < events.size(); ++i) {
    Event e = events[i];
    if (e.channel == c.lcm.controls_channel) {
      if (held) {  // the later control arrives first, then the held, earlier one
        faulty.push_back(e);
        faulty.push_back(*held);
        held.reset();
        ++swapped;
        continue;
      }
      if (++control_no % 40 == 0 && clear_of(i, marks)) {
        held = e;
        continue;
      }
    }
    faulty.push_back(e);
    if (e.channel != c.lcm.frame_channel) continue;
    kincal::frame_t f;
    f.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
    const bool usable =
        valid.count(f.utime) && valid.count(prev_frame_utime) && i > 10 && clear_of(i, marks);
    prev_frame_utime = f.utime;
    if (!usable) continue;
    ++frame_no;
    if (frame_no % 50 == 0) {  // the same frame twice: a repeated timestamp
      faulty.push_back(e);
      ++repeated;
    } else if (frame_no % 50 == 25) {  // a frame stamped 0.1 s before its predecessor
      f.utime -= 100'000;
      faulty.back().data = Encode(f);
      ++earlier;
    }
  }
  // The clock jumps 3 s forward (a new run) and later 20 s back (a new time base).
  ShiftFrom(&faulty, jump_forward_at, 3'000'000, c);
  ShiftFrom(&faulty, jump_back_at, -20'000'000, c);
  const std::string path = TempPath("faulty.lcm");
  WriteLog(path, faulty);
  ASSERT_GT(repeated, 3);
  ASSERT_GT(earlier, 3);
  ASSERT_GT(swapped, 3);

  DaemonCounters clean_k, k;
  const Checkpoint clean = Replay(c, c.record.path, &clean_k);
  const Checkpoint e = Replay(c, path, &k);
  std::cout << "injected: " << repeated << " repeated, " << earlier << " earlier, " << swapped
            << " swapped controls; discarded at the reset: " << k.discarded_at_reset << "\n";
  EXPECT_EQ(k.frames_out_of_order, repeated + earlier)
      << "rule: a pose not after the last one is not used";
  EXPECT_EQ(k.controls_out_of_order, swapped) << "rule: a control older than the newest is ignored";
  EXPECT_EQ(k.time_resets, 1)
      << "rule: a clock jumping back by more than max_pose_gap_s starts a new time base";
  EXPECT_EQ(k.run_resets, clean_k.run_resets + 1)
      << "rule: a gap longer than max_pose_gap_s starts a new run";
  EXPECT_LT(k.discarded_at_reset, 100) << "only what was in flight at the jump";
  EXPECT_EQ(k.frames_captured, clean_k.frames_captured + repeated);
  ExpectWithin3Sigma(e, Truth(c));
  EXPECT_LT(Nnde(e, Truth(c)), 2.0 * Nnde(clean, Truth(c)) + 1e-4);
}

// A loaded receiver (load ~6 on 2 cores): each control message reaches the daemon a random
// time after it was sent (exponential, mean 15 ms), with stalls of 100-300 ms in 2 % of the
// messages that hold back the ones behind (delivery keeps the order). The robot stamps its
// messages on its own clock, whose epoch is unrelated to the daemon's (seconds since boot).
// `p95_ms` receives the p95 of the added delays.
std::vector<Event> DeliverControlsUnderLoad(const std::vector<Event>& clean, const DaemonConfig& c,
                                            uint64_t seed, double* p95_ms) {
  std::vector<double> added_ms;
  std::mt19937_64 rng(seed);
  std::exponential_distribution<double> delay(1.0 / 0.015);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<Event> out;
  int64_t last_receive = 0;
  for (const Event& e : clean) {
    if (e.channel != c.lcm.controls_channel) {
      out.push_back(e);
      continue;
    }
    kincal::controls_t m;
    m.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
    double d = 0.0002 + delay(rng);
    if (u01(rng) < 0.02) d += 0.1 + 0.2 * u01(rng);
    last_receive = std::max(last_receive, m.utime + static_cast<int64_t>(d * 1e6));
    added_ms.push_back(static_cast<double>(last_receive - m.utime) / 1000.0);
    m.sender_utime = m.utime - clean.front().utime + 5'000'000;  // the robot's clock
    out.push_back({e.channel, last_receive, Encode(m)});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Event& a, const Event& b) { return a.utime < b.utime; });
  std::sort(added_ms.begin(), added_ms.end());
  *p95_ms = added_ms[static_cast<size_t>(0.95 * static_cast<double>(added_ms.size()))];
  return out;
}

TEST(TimingFaults, ControlsDelayedByALoadedReceiverAreRestampedFromTheSenderClock) {
  DaemonConfig c = SimConfig(30);
  c.record.path = TempPath("load_clean.lcm");
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
  }
  const std::string loaded = TempPath("load_jittered.lcm");
  double true_p95_ms = 0;
  WriteLog(loaded, DeliverControlsUnderLoad(ReadLog(c.record.path), c, 7, &true_p95_ms));
  // Judged on the filter's own estimates (the tier the stamps feed; the batch calibration,
  // fitted on fewer poses, is checked within 3 sigma below).
  DaemonCounters clean_k, received_k, mapped_k;
  Checkpoint clean, received, mapped;
  Replay(c, c.record.path, &clean_k, &clean);
  c.robot.control_stamp = ControlStamp::kReceive;  // the obvious alternative
  Replay(c, loaded, &received_k, &received);
  c.robot.control_stamp = ControlStamp::kMapped;  // the default
  const Checkpoint mapped_calibration = Replay(c, loaded, &mapped_k, &mapped);
  const auto truth = Truth(c);
  std::cout << "parameter error (NNDE): clean " << Nnde(clean, truth) << "; controls delayed by "
            << "load, stamped on receipt " << Nnde(received, truth) << " ("
            << received_k.poses_gated << " gated), mapped from the robot's clock "
            << Nnde(mapped, truth) << " (" << mapped_k.poses_gated << " gated); jitter p95 "
            << mapped_k.control_jitter_p95_ms << " ms, max " << mapped_k.control_jitter_max_ms
            << " ms\n";
  // Receive stamps carry the load into the estimate: gated poses, a worse estimate.
  EXPECT_GT(received_k.poses_gated, 10);
  EXPECT_GT(Nnde(received, truth), 2.0 * Nnde(clean, truth));
  // Mapped stamps: as good as the clean run, nothing gated, honest, and the jitter it
  // removed is reported (the p95 of the delays added, less the least: 0.2 ms).
  ExpectWithin3Sigma(mapped, truth);
  ExpectWithin3Sigma(mapped_calibration, truth);
  EXPECT_EQ(mapped_calibration.source, "batch");
  EXPECT_LE(Nnde(mapped, truth), 1.2 * Nnde(clean, truth) + 1e-4);
  EXPECT_EQ(mapped_k.poses_gated, clean_k.poses_gated);
  EXPECT_EQ(mapped_k.filter_resets, 0);
  EXPECT_EQ(mapped_k.control_clock_steps, 0);
  EXPECT_NEAR(mapped_k.control_jitter_p95_ms, true_p95_ms, 2.0);
  EXPECT_GT(mapped_k.control_jitter_max_ms, 100.0);
  EXPECT_EQ(received_k.control_jitter_p95_ms, -1.0) << "not measured on receive stamps";
}

TEST(MeasurementFaults, TenPercentReflectionsLeaveTheErrorWithin1_2TimesTheCleanCase) {
  // The same simulated runs (same image noise) with and without a marker-like blob
  // within a plate's size of the target in 10 % of the frames.
  double clean_sum = 0, faulty_sum = 0;
  int64_t gated = 0, lost = 0;
  for (const uint64_t seed : {21u, 22u, 23u}) {
    DaemonConfig c = SimConfig(30);
    c.sim.seed = seed;
    const std::unique_ptr<Daemon> clean_owner = Daemon::Create(c).value();
    Daemon& clean = *clean_owner;
    ASSERT_EQ(clean.Run(), 0);
    c.sim.reflection_prob = 0.10;
    const std::unique_ptr<Daemon> faulty_owner = Daemon::Create(c).value();
    Daemon& faulty = *faulty_owner;
    ASSERT_EQ(faulty.Run(), 0);
    const auto truth = Truth(c);
    // The filter's estimates (the tier the gate protects); the calibration within 3 sigma.
    clean_sum += Nnde(clean.FilterEstimate(), truth);
    faulty_sum += Nnde(faulty.FilterEstimate(), truth);
    ExpectWithin3Sigma(faulty.FilterEstimate(), truth);
    ExpectWithin3Sigma(faulty.Estimate(), truth);
    gated += faulty.counters().poses_gated;
    lost += clean.counters().poses_valid - faulty.counters().poses_valid;
  }
  std::cout << "parameter error (NNDE), mean of 3 seeds: clean " << clean_sum / 3
            << ", with 10 % reflections " << faulty_sum / 3 << "; " << gated << " poses gated, "
            << lost << " fewer valid poses\n";
  EXPECT_LE(faulty_sum, 1.2 * clean_sum);
}

TEST(MeasurementFaults, AHiddenMarkerGivesNoPoseAndTheEstimateHolds) {
  DaemonConfig c = SimConfig(30);
  const std::unique_ptr<Daemon> clean_owner = Daemon::Create(c).value();
  Daemon& clean = *clean_owner;
  ASSERT_EQ(clean.Run(), 0);
  c.sim.occlusion_prob = 0.2;  // one marker hidden in 20 % of the frames: three markers
  const std::unique_ptr<Daemon> faulty_owner = Daemon::Create(c).value();
  Daemon& faulty = *faulty_owner;
  ASSERT_EQ(faulty.Run(), 0);
  const auto kc = clean.counters(), kf = faulty.counters();
  const double kept = static_cast<double>(kf.poses_valid) / static_cast<double>(kc.poses_valid);
  EXPECT_NEAR(kept, 0.8, 0.04) << "a frame with the wrong number of markers gives no pose";
  EXPECT_EQ(kf.poses_valid + kf.poses_invalid, kc.poses_valid + kc.poses_invalid);
  ExpectWithin3Sigma(faulty.Estimate(), Truth(c));
}

TEST(MeasurementFaults, AFarOffPoseFailsTheGateAndLeavesTheStateAlone) {
  const System sys = MakeSystem("diffdrive", {}).value();
  OnlineCalibratorOptions opt;
  opt.noise.control_psd = {0.0, 0.0};
  OnlineCalibrator cal(sys, opt, 0);
  const double w[2] = {5.0, 5.0};
  cal.AddControl(0, w);
  VecN<kMaxState> p(3);
  p << 0.031, 0.031, 0.148;
  StateMat P = StateMat::Zero(3, 3);
  P.diagonal() << 1e-8, 1e-8, 1e-6;
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 1e-6, 1e-5).asDiagonal();
  cal.Initialize(0, Eigen::Vector3d::Zero(), R, p, P);
  const Eigen::Vector3d moved(5.0 * 0.031 * 0.1, 0.0, 0.0);  // 0.1 s straight ahead
  const UpdateResult good = cal.AddPose(100'000'000, moved, R, 16.27);
  EXPECT_TRUE(good.ok);
  EXPECT_FALSE(good.gated);
  const StateVec before = cal.state();
  const UpdateResult bad =
      cal.AddPose(200'000'000, moved + Eigen::Vector3d(0.5, 0.0, 0.0), R, 16.27);
  EXPECT_FALSE(bad.ok);
  EXPECT_TRUE(bad.gated);
  EXPECT_GT(bad.nis, 1e4);
  EXPECT_EQ(cal.update_count(), 1);
  EXPECT_EQ(cal.params(), before.segment(3, 3)) << "a gated pose does not touch the parameters";
}

TEST(Divergence, AnOverconfidentWrongPriorIsCaughtAndRestartedFromABatchFit) {
  DaemonConfig c = SimConfig(30);
  // 25 % off and claiming to be within 1 %: the filter cannot move far enough, its
  // innovations run far beyond their prediction, and the daemon must notice and re-fit
  // (once: a re-fit that explains the poses ends the episode).
  c.robot.guess = {{"r_l", 0.039}, {"r_r", 0.024}, {"d", 0.185}};
  c.robot.guess_sigma_fraction = 0.01;
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
  Daemon& d = *d_owner;
  ASSERT_EQ(d.Run(), 0);
  const DaemonCounters k = d.counters();
  EXPECT_EQ(k.filter_resets, 1);
  ExpectWithin3Sigma(d.Estimate(), Truth(c));
  ExpectWithin3Sigma(d.FilterEstimate(), Truth(c));
  // The restart inflates the re-fit's covariance by 4: the 3-sigma checks above would pass
  // any sigma, so each tier's sigma is bounded by the same tier's from the right guess
  // (issue 34; measured: batch 1.03-1.04x, filter 0.13-0.16x: it restarts from the batch).
  DaemonConfig right = SimConfig(30);
  const std::unique_ptr<Daemon> clean_owner = Daemon::Create(right).value();
  Daemon& clean = *clean_owner;
  ASSERT_EQ(clean.Run(), 0);
  for (const auto& [restarted, reference] :
       {std::pair{d.Estimate(), clean.Estimate()}, {d.FilterEstimate(), clean.FilterEstimate()}}) {
    ASSERT_EQ(restarted.names, reference.names);
    for (size_t i = 0; i < restarted.names.size(); ++i) {
      const int j = static_cast<int>(i);
      const double sigma = std::sqrt(restarted.covariance(j, j));
      const double ref = std::sqrt(reference.covariance(j, j));
      std::cout << restarted.source << " " << restarted.names[i] << ": sigma " << sigma
                << " after the restart, " << ref << " from the right guess\n";
      EXPECT_LT(sigma, 2.0 * ref) << restarted.source << " " << restarted.names[i];
    }
  }
}

// A million frames through the whole pipeline (a short log replayed in a loop): resident
// memory stays flat and throughput does not fall.
TEST(Soak, AMillionFramesWithFlatMemory) {
  DaemonConfig c = ReadDaemonConfig(kConfigDir + "/kincald_thesis.yaml").value();
  c.lcm.url = "memq://";
  c.sim.speed = 0;
  c.sim.duration_s = 60;
  c.record.path = TempPath("soak.lcm");
  int64_t per_loop = 0;
  {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    ASSERT_EQ(d.Run(), 0);
    per_loop = d.counters().frames_captured;
  }
  ASSERT_GT(per_loop, 200);
  DaemonConfig r = c;
  r.source = SourceKind::kReplay;
  r.replay.path = c.record.path;
  r.replay.speed = 0;
  r.replay.loops = static_cast<int>(1'000'000 / per_loop + 1);
  r.record.path.clear();
  r.checkpoint.path = TempPath("soak.json");
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(r).value();
  Daemon& d = *d_owner;
  struct Sample {
    int64_t frames;
    double rss_mb;
    double t_s;
  };
  std::vector<Sample> samples;
  std::atomic<bool> done{false};
  std::thread monitor([&] {
    const auto t0 = std::chrono::steady_clock::now();
    while (!done.load()) {
      std::ifstream in("/proc/self/status");
      std::string line;
      double rss = 0;
      while (std::getline(in, line)) {
        if (line.rfind("VmRSS:", 0) == 0) rss = std::stod(line.substr(6)) / 1024.0;
      }
      samples.push_back(
          {d.counters().frames_captured, rss,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()});
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  });
  ASSERT_EQ(d.Run(), 0);
  done.store(true);
  monitor.join();
  const DaemonCounters k = d.counters();
  EXPECT_GE(k.frames_captured, 1'000'000);
  EXPECT_EQ(k.frames_dropped_queue, 0);
  EXPECT_EQ(k.time_resets, 0);
  EXPECT_EQ(k.frames_out_of_order, 0);
  ASSERT_GT(samples.size(), 20u);
  // Memory: after the first fifth of the frames, resident size grows by less than 8 MB.
  auto at = [&](double fraction) {
    for (const auto& s : samples) {
      if (s.frames >= fraction * static_cast<double>(k.frames_captured)) return s;
    }
    return samples.back();
  };
  const Sample s20 = at(0.2), s40 = at(0.4), s80 = at(0.8), end = samples.back();
  double peak = 0;
  for (const auto& s : samples) {
    if (s.frames >= s20.frames) peak = std::max(peak, s.rss_mb);
  }
  std::cout << "soak: " << k.frames_captured << " frames in " << end.t_s << " s; RSS " << s20.rss_mb
            << " MB at 20 %, " << peak << " MB peak after, " << end.rss_mb << " MB at the end\n";
  EXPECT_LT(peak - s20.rss_mb, 8.0);
  // Throughput is printed for a reader, not asserted: wall-clock speed depends on what
  // else the machine runs (a clean-clone CI run failed this way with a build beside it);
  // scripts/bench measures replay speed.
  const double early = (s40.frames - s20.frames) / (s40.t_s - s20.t_s);
  const double late = (end.frames - s80.frames) / (end.t_s - s80.t_s);
  std::cout << "soak: " << early << " frames/s early, " << late << " late\n";
}

}  // namespace
}  // namespace kincal::daemon
