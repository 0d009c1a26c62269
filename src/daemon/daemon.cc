// kincald's pipeline: the threads and how they are wired. The stages live in their own
// files: the sources (*_source.cc, chosen by MakeSource), the pose stage (pose_stage.cc),
// the filter stage (filter_stage.cc, with its time base), the LCM messages (messages.cc),
// health (health.cc) and the recorder (recorder.cc).
#include "kincal/daemon/daemon.h"

#include <spdlog/spdlog.h>

#include <kincal/frame_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <optional>
#include <thread>

#include "daemon/bounded_queue.h"
#include "daemon/control_input.h"
#include "daemon/counters.h"
#include "daemon/filter_stage.h"
#include "daemon/health.h"
#include "daemon/latency_histogram.h"
#include "daemon/messages.h"
#include "daemon/pose_stage.h"
#include "daemon/recorder.h"
#include "daemon/sources.h"
#include "kincal/scenario.h"
#include "kincal/system.h"

namespace kincal::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// A live device that failed is reopened after 0.25 s, 0.5 s, ... up to 5 s between tries.
constexpr double kReopenFirstWaitS = 0.25;
constexpr double kReopenMaxWaitS = 5.0;
// The filter thread waits this long for a pose, then looks at the controls again.
constexpr auto kPoseWait = std::chrono::milliseconds(20);
// A control clock jump is held this long (live) for the poses to show it too.
constexpr TimeNs kHeldJumpWaitNs = kNsPerSecond;
// After a simulated robot's frames end, the last controls it published over LCM arrive.
constexpr auto kLastControlsWait = std::chrono::milliseconds(200);
// Poses held while waiting for their controls: at least this many.
constexpr int kMinPendingPoses = 256;

}  // namespace

struct Daemon::Impl {
  DaemonConfig cfg;
  System sys;
  VisionSetup vis;
  std::unique_ptr<FrameSource> source;
  SourceCapabilities caps;

  std::unique_ptr<lcm::LCM> lcm;
  std::mutex lcm_mu;
  std::unique_ptr<Recorder> recorder;

  BoundedQueue<Frame> frame_q;
  BoundedQueue<PoseSample> pose_q;
  BoundedQueue<ControlSample> control_q;

  std::atomic<bool> stop{false};
  std::atomic<bool> source_done{false};
  std::atomic<bool> controls_done{false};
  std::atomic<bool> filter_done{false};
  CounterSet counters;
  std::atomic<TimeNs> last_frame_mono{0};

  std::mutex status_mu;  // guards what follows
  std::string source_error, last_frame_error, last_reject;
  LatencyHistogram latency_total, latency_window;
  Checkpoint estimate;

  std::optional<Checkpoint> resume;
  HealthReporter health;

  explicit Impl(DaemonConfig c)
      : cfg(std::move(c)),
        sys(MakeSystem(cfg.robot.model, cfg.robot.effects)),
        vis(LoadVisionSetup(cfg)),
        source(MakeSource(
            cfg, vis,
            [this](const void* data, size_t n, int64_t utime) { OnControls(data, n, utime); },
            [this](const std::string& ch, const void* data, size_t n) {
              PublishRaw(ch, data, n);
            })),
        caps(source->capabilities()),
        frame_q(static_cast<size_t>(cfg.queues.frames), QueuePolicy()),
        pose_q(static_cast<size_t>(cfg.queues.poses), QueuePolicy()),
        control_q(static_cast<size_t>(cfg.queues.controls), QueuePolicy()) {}

  // Live: fresh data matters more than old (drop the oldest); lossless: block.
  FullPolicy QueuePolicy() const {
    return caps.lossless ? FullPolicy::kBlock : FullPolicy::kDropOldest;
  }

  // ---- output -------------------------------------------------------------------------
  template <typename Msg>
  void Publish(const std::string& channel, int64_t utime, const Msg& m, bool network = true) {
    if (network && lcm) {
      std::lock_guard lock(lcm_mu);
      lcm->publish(channel, &m);
    }
    if (recorder) recorder->WriteMessage(channel, utime, m);
  }
  void PublishRaw(const std::string& channel, const void* data, size_t n) {
    if (!lcm) return;
    std::lock_guard lock(lcm_mu);
    lcm->publish(channel, data, static_cast<unsigned>(n));
  }

  // ---- controls -----------------------------------------------------------------------
  // Every control message, from LCM, the simulated robot or the log, comes through here.
  void OnControls(const void* data, size_t n, int64_t receive_utime) {
    if (recorder) recorder->Write(cfg.lcm.controls_channel, receive_utime, data, n);
    ControlSample s;
    thread_local std::string why;
    const bool sender_stamp = cfg.robot.control_stamp == ControlStamp::kSender;
    if (!DecodeControls(data, n, sys.model(), sender_stamp, receive_utime, &s, &why)) {
      if (counters.messages_rejected.fetch_add(1) == 0) {
        spdlog::warn("rejected a control message: {}", why);
      }
      std::lock_guard lock(status_mu);
      last_reject = why;
      return;
    }
    counters.controls_received.fetch_add(1);
    control_q.Push(s);
  }

  // ---- capture thread -----------------------------------------------------------------
  void CaptureLoop() {
    Frame f;
    kincal::frame_t msg;
    std::vector<uint8_t> png;
    while (!stop.load()) {
      std::string error;
      const SourceStatus st = source->Next(&f, 100, &error);
      if (st == SourceStatus::kEnd) break;
      if (st == SourceStatus::kTimeout) continue;
      if (st == SourceStatus::kError) {
        SetSourceError(error);
        spdlog::error("source {}: {}", source->name(), error);
        if (!caps.can_reopen || !ReopenWithBackoff()) break;
        continue;
      }
      counters.frames_captured.fetch_add(1);
      last_frame_mono.store(MonotonicNs());
      if (recorder || cfg.lcm.publish_frames) {
        FillFrameMessage(f, cfg.record.frame_encoding, &png, &msg);
        Publish(cfg.lcm.frame_channel, f.utime, msg, cfg.lcm.publish_frames);
      }
      frame_q.Push(f);
    }
    source_done.store(true);
    frame_q.Close();
    if (caps.carries_controls) {
      controls_done.store(true);  // the source carried the controls: there are no more
    } else if (caps.controls_end_with_frames) {
      std::this_thread::sleep_for(kLastControlsWait);
      controls_done.store(true);
    }
  }

  void SetSourceError(const std::string& error) {
    std::lock_guard lock(status_mu);
    source_error = error;
  }

  // A live device failed: close it and open it again, waiting longer each time, until it
  // is back or the daemon is stopped. Health says so meanwhile.
  bool ReopenWithBackoff() {
    double wait_s = kReopenFirstWaitS;
    while (!stop.load()) {
      const TimeNs until = MonotonicNs() + SecondsToNs(wait_s);
      while (!stop.load() && MonotonicNs() < until) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      if (stop.load()) return false;
      const Status reopened = source->Reopen();
      if (reopened.ok()) {
        counters.source_restarts.fetch_add(1);
        SetSourceError("");
        spdlog::info("source {}: reopened, capturing again", source->name());
        return true;
      }
      wait_s = std::min(kReopenMaxWaitS, 2 * wait_s);
      SetSourceError(reopened.message() + " (retrying every " +
                     std::to_string(wait_s).substr(0, 4) + " s)");
    }
    return false;
  }

  // ---- detection / pose thread --------------------------------------------------------
  void DetectionLoop() {
    PoseStage stage(cfg.pose, cfg.detector, vis);
    Frame f;
    PoseSample p;
    kincal::pose_t pose_msg{};
    kincal::markers_t markers_msg{};
    std::string error;
    while (true) {
      if (!frame_q.Pop(f, std::chrono::milliseconds(100))) {
        if (frame_q.closed_and_empty()) break;
        continue;
      }
      if (!stage.Process(f, &p, &error)) {
        counters.frames_bad.fetch_add(1);
        std::lock_guard lock(status_mu);
        last_frame_error = error;
        continue;
      }
      (p.valid ? counters.poses_valid : counters.poses_invalid).fetch_add(1);
      // Publish the pose (and markers) now: this is the frame-to-publish latency.
      FillPoseMessage(p, &pose_msg);
      Publish(cfg.lcm.pose_channel, p.utime, pose_msg);
      counters.poses_published.fetch_add(1);
      if (cfg.lcm.publish_markers) {
        FillMarkersMessage(p, cfg.pose.sigma_px, &markers_msg);
        Publish(cfg.lcm.markers_channel, p.utime, markers_msg);
      }
      if (p.arrival_mono_ns > 0) {
        const double ms = NsToSeconds(MonotonicNs() - p.arrival_mono_ns) * 1e3;
        std::lock_guard lock(status_mu);
        latency_total.Add(ms);
        latency_window.Add(ms);
      }
      pose_q.Push(p);
    }
    pose_q.Close();
  }

  // ---- filter thread ------------------------------------------------------------------
  FilterOutputs StageOutputs() {
    FilterOutputs out;
    out.params = [this](int64_t utime, const kincal::params_t& m) {
      Publish(cfg.lcm.params_channel, utime, m);
    };
    out.model_check = [this](int64_t utime, const kincal::model_check_t& m) {
      Publish(cfg.lcm.model_check_channel, utime, m);
    };
    out.estimate = [this](const Checkpoint& ck) {
      std::lock_guard lock(status_mu);
      estimate = ck;
    };
    out.checkpoint_due = [this] { WriteCheckpointLogged(); };
    return out;
  }

  // Merges poses and controls in time order: a pose goes to the filter stage once the
  // controls up to its time are in, or the controls have ended, or (live) it has waited
  // robot.max_control_delay_s.
  void FilterLoop() {
    FilterPrior prior = ConfiguredPrior(sys, cfg.robot, cfg.file);
    if (resume) {
      const int matched = ResumeFrom(sys, *resume, &prior);
      spdlog::info("resumed {} of {} parameters from {} ({} updates)", matched, sys.num_params(),
                   cfg.checkpoint.resume, resume->update_count);
    }
    FilterStage stage(
        sys, FilterStageOptionsFrom(cfg), std::move(prior),
        [this](ControlSample* c) { return control_q.TryPop(*c); }, StageOutputs(), &counters);
    PoseRing pending(static_cast<size_t>(std::max(4 * cfg.queues.poses, kMinPendingPoses)));
    const TimeNs max_delay_ns = SecondsToNs(cfg.robot.max_control_delay_s);
    const bool lossless = caps.lossless;
    PoseSample p;
    while (true) {
      const bool got = pose_q.Pop(p, kPoseWait);
      stage.DrainControls(MonotonicNs());
      if (got) {
        if (pending.full()) {  // hold no more: use the oldest with what we have
          stage.AddPose(pending.front(), MonotonicNs());
          pending.pop();
        }
        pending.push(p);
      }
      const bool poses_over = !got && pose_q.closed_and_empty();
      const bool no_more_controls =
          controls_done.load() && control_q.size() == 0 && !stage.holding_jump();
      if (no_more_controls) stage.DrainControls(MonotonicNs());
      // The controls jumped back and the poses did not follow: the controls alone start
      // the new time base (live after a while; lossless when the poses have ended).
      if (stage.holding_jump() && pending.empty() &&
          (poses_over ||
           (!lossless && MonotonicNs() - stage.held_since_mono_ns() > kHeldJumpWaitNs))) {
        stage.TakeControlJump(MonotonicNs());
      }
      while (!pending.empty()) {
        const PoseSample& f = pending.front();
        const bool waited = !lossless && MonotonicNs() - f.arrival_mono_ns > max_delay_ns;
        if (!(stage.ControlsCover(f) || no_more_controls || (poses_over && stop.load()) ||
              waited)) {
          break;
        }
        stage.AddPose(f, MonotonicNs());
        pending.pop();
      }
      if (poses_over && (no_more_controls || stop.load() || !lossless)) {
        stage.DrainControls(MonotonicNs());
        for (; !pending.empty(); pending.pop()) stage.AddPose(pending.front(), MonotonicNs());
        break;
      }
    }
    stage.Finish();
    filter_done.store(true);
  }

  void WriteCheckpointLogged() {
    Checkpoint ck;
    {
      std::lock_guard lock(status_mu);
      ck = estimate;
    }
    if (ck.names.empty()) return;
    try {
      WriteCheckpoint(cfg.checkpoint.path, ck);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
    }
  }

  // An unrecoverable error in a pipeline thread: report it, close the queues so every
  // thread drains and ends, and make Run() return 1.
  void Fatal(const std::string& what) {
    spdlog::error("{}", what);
    {
      std::lock_guard lock(status_mu);
      if (source_error.empty()) source_error = what;
    }
    stop.store(true);
    controls_done.store(true);
    frame_q.Close();
    pose_q.Close();
    control_q.Close();
    filter_done.store(true);
  }

  // ---- health (main thread) -----------------------------------------------------------
  void PublishHealth(double period_s) {
    HealthStatus s;
    s.source_name = source->name();
    s.source_done = source_done.load();
    s.since_last_frame_ns = MonotonicNs() - last_frame_mono.load();
    s.expects_lcm_controls = !caps.carries_controls;
    s.controls_channel = cfg.lcm.controls_channel;
    if (recorder) s.recorder_error = recorder->error();
    {
      std::lock_guard lock(status_mu);
      s.source_error = source_error;
      s.last_frame_error = last_frame_error;
      s.last_reject = last_reject;
      s.latency_p50_ms = latency_window.Percentile(0.5);
      s.latency_p99_ms = latency_window.Percentile(0.99);
      latency_window.Reset();
    }
    kincal::health_t h;
    health.Build(Snapshot(), s, period_s, RealtimeUtime(), &h);
    Publish(cfg.lcm.health_channel, h.utime, h);
    if (!h.message.empty()) spdlog::warn("health: {}", h.message);
  }

  // Every counter: the pipeline's own, and those the components keep.
  DaemonCounters Snapshot() const {
    DaemonCounters c = counters.Load();
    c.frames_dropped_device = source->device_drops();
    c.frames_dropped_queue = frame_q.dropped();
    c.frames_bad += source->rejected();
    c.poses_dropped_queue = pose_q.dropped();
    c.controls_dropped_queue = control_q.dropped();
    c.log_events_written = recorder ? recorder->written() : 0;
    c.log_events_lost = recorder ? recorder->lost() : 0;
    return c;
  }
};

Daemon::Daemon(DaemonConfig config) {
  Validate(config);
  impl_ = std::make_unique<Impl>(std::move(config));
  Impl& d = *impl_;
  const DaemonConfig& cfg = d.cfg;
  if (!cfg.checkpoint.resume.empty()) {
    d.resume = ReadCheckpoint(cfg.checkpoint.resume);
    if (d.resume->model != d.sys.model().name()) {
      throw std::runtime_error(cfg.checkpoint.resume + ": checkpoint is for model '" +
                               d.resume->model + "', the config says '" +
                               std::string(d.sys.model().name()) + "'");
    }
  }
  d.lcm = std::make_unique<lcm::LCM>(cfg.lcm.url);
  if (!d.lcm->good()) {
    throw std::runtime_error(
        "LCM: cannot open '" + (cfg.lcm.url.empty() ? std::string("default URL") : cfg.lcm.url) +
        "' (for udpm on loopback: `ip link set lo multicast on` and a 224.0.0.0/4 route)");
  }
  if (!cfg.record.path.empty()) {
    d.recorder = std::make_unique<Recorder>(
        cfg.record.path, static_cast<size_t>(cfg.queues.recorder),
        d.caps.lossless ? FullPolicy::kBlock : FullPolicy::kDropNewest, cfg.record.flush_every_s);
  }
  if (!d.caps.carries_controls) {
    d.lcm->subscribeFunction(
        cfg.lcm.controls_channel,
        +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Impl* self) {
          // Receive stamp on the pipeline's time base (monotonic, mapped once): an NTP step of
          // the realtime clock does not make controls jump against frames.
          self->OnControls(rbuf->data, rbuf->data_size, PipelineUtime(MonotonicNs()));
        },
        &d);
  }
}

Daemon::~Daemon() = default;

void Daemon::Stop() { impl_->stop.store(true); }

int Daemon::Run() {
  Impl& d = *impl_;
  if (const Status started = d.source->Start(); !started.ok()) {
    spdlog::error("{}", started.message());
    d.SetSourceError(started.message());
    return 1;
  }
  d.last_frame_mono.store(MonotonicNs());
  spdlog::info("kincald: source {}, model {}{}, filter {}, LCM {}{}", d.source->name(),
               d.cfg.robot.model, d.cfg.robot.effects.empty() ? "" : " + effects",
               d.cfg.filter.type, d.cfg.lcm.url.empty() ? "default" : d.cfg.lcm.url,
               d.cfg.record.path.empty() ? "" : ", recording to " + d.cfg.record.path);
  // A thread that fails records why and stops the pipeline; it never takes the process down.
  auto guarded = [&d](const char* name, void (Impl::*loop)()) {
    return std::thread([&d, name, loop] {
      try {
        (d.*loop)();
      } catch (const std::exception& e) {
        d.Fatal(std::string(name) + " thread: " + e.what());
      }
    });
  };
  std::thread capture = guarded("capture", &Impl::CaptureLoop);
  std::thread detection = guarded("detection", &Impl::DetectionLoop);
  std::thread filter = guarded("filter", &Impl::FilterLoop);
  const bool subscribe = !d.caps.carries_controls;
  std::thread lcm_thread([&d, subscribe] {
    while (!d.filter_done.load()) {
      if (subscribe) {
        d.lcm->handleTimeout(50);
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  });
  const auto period = std::chrono::duration<double>(1.0 / d.cfg.health_rate_hz);
  auto next_health = Clock::now() + std::chrono::duration_cast<Clock::duration>(period);
  bool stopping = false;
  while (!d.filter_done.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (d.stop.load() && !stopping) {
      stopping = true;
      spdlog::info("kincald: stopping: draining queues");
      d.source->Stop();
      d.controls_done.store(true);
    }
    if (Clock::now() >= next_health) {
      d.PublishHealth(period.count());
      next_health += std::chrono::duration_cast<Clock::duration>(period);
    }
  }
  capture.join();
  detection.join();
  filter.join();
  lcm_thread.join();
  d.source->Stop();
  d.PublishHealth(period.count());
  if (d.recorder) d.recorder->Close();
  spdlog::info("kincald: {}", SummaryLine(counters()));
  std::lock_guard lock(d.status_mu);
  return d.source_error.empty() ? 0 : 1;
}

Checkpoint Daemon::Estimate() const {
  std::lock_guard lock(impl_->status_mu);
  return impl_->estimate;
}

DaemonCounters Daemon::counters() const {
  DaemonCounters c = impl_->Snapshot();
  std::lock_guard lock(impl_->status_mu);
  c.latency_p50_ms = impl_->latency_total.Percentile(0.5);
  c.latency_p99_ms = impl_->latency_total.Percentile(0.99);
  c.latency_max_ms = impl_->latency_total.max_ms();
  return c;
}

}  // namespace kincal::daemon
