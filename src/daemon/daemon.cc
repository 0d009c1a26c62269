// kincald's pipeline: the threads and how they are wired. The stages live in their own
// files: the sources (*_source.cc, chosen by MakeSource), the pose stage (pose_stage.cc),
// the online estimator the filter thread drives (src/online/, set up by filter_setup.cc),
// the LCM messages (messages.cc), health (health.cc) and the recorder (recorder.cc).
#include "kincal/daemon/daemon.h"

#include <spdlog/spdlog.h>

#include <kincal/calibration_t.hpp>
#include <kincal/health_t.hpp>
#include <kincal/model_check_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <optional>
#include <thread>

#include "daemon/batch_worker.h"
#include "daemon/bounded_queue.h"
#include "daemon/capture_stage.h"
#include "daemon/control_input.h"
#include "daemon/counters.h"
#include "daemon/detection_stage.h"
#include "daemon/drive_link.h"
#include "daemon/filter_setup.h"
#include "daemon/guidance.h"
#include "daemon/health.h"
#include "daemon/path_lock.h"
#include "daemon/pose_control_merge.h"
#include "daemon/pose_input.h"
#include "daemon/pose_stage.h"
#include "daemon/publisher.h"
#include "daemon/sources.h"
#include "kincal/system.h"

namespace kincal::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// After a simulated robot's frames end, the last controls it published over LCM arrive.
constexpr auto kLastControlsWait = std::chrono::milliseconds(200);
// Poses held while waiting for their controls: at least this many.
constexpr int kMinPendingPoses = 256;

// What stops the daemon from opening (a file, the source, a lock, LCM); thrown while it is
// built and caught in Daemon::Create, never outside this file.
class StartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <typename T>
T OrStartupError(StatusOr<T> v) {
  if (!v.ok()) throw StartupError(v.status().message());
  return std::move(v).value();
}

}  // namespace

struct Daemon::Impl {
  DaemonConfig cfg;
  System sys;
  VisionSetup vis;
  std::unique_ptr<DriveLink> drive;  // guidance.drive: before the source that drives by it
  std::unique_ptr<FrameSource> source;
  SourceCapabilities caps;

  Publisher out;

  BoundedQueue<Frame> frame_q;
  BoundedQueue<PoseSample> pose_q;
  BoundedQueue<ControlSample> control_q;

  std::atomic<bool> stop{false};
  std::atomic<bool> source_done{false};
  std::atomic<bool> controls_done{false};
  std::atomic<bool> filter_done{false};
  // The filter thread's stage while it runs, so that a stop can end a running batch early
  // (FilterStage::CancelBatch; the last batch over everything replaces it).
  std::mutex stage_mu;
  FilterStage* stage = nullptr;
  CounterSet counters;
  ControlReceiver intake;
  PoseReceiver logged_poses;  // a replayed log without frames: its poses
  std::unique_ptr<CaptureStage> capture;
  PoseStage pose_stage;
  std::unique_ptr<PreviewStage> preview;  // preview.enabled
  DetectionStage detection;

  // The status of the last params_t published; a health message reports it. The lock
  // orders the two publications, so that a log never shows health and params disagreeing.
  std::mutex filter_report_mu;
  int filter_status = 0;

  std::mutex status_mu;  // guards what follows
  std::string source_error, model_check_evidence;
  std::string checkpoint_error;           // the last checkpoint write's failure (empty: written)
  Checkpoint estimate;                    // the filter's, until there is a batch calibration
  std::optional<Checkpoint> calibration;  // the batch tier's calibration in force

  std::optional<Checkpoint> resume;
  PathLock record_lock, checkpoint_lock;  // held for the daemon's life
  HealthReporter health;
  std::unique_ptr<Guidance> guidance;  // guidance.enabled; after `out`: stopped before it

  explicit Impl(DaemonConfig c)
      : cfg(std::move(c)),
        sys(OrStartupError(MakeSystem(cfg.robot.model, cfg.robot.effects))),
        vis(OrStartupError(LoadVisionSetup(cfg))),
        drive(MakeDriveLink(cfg, vis)),
        source(OrStartupError(
            MakeSource(cfg, vis, std::bind_front(&ControlReceiver::OnMessage, &intake),
                       std::bind_front(&Publisher::PublishRaw, &out), drive.get(),
                       std::bind_front(&PoseReceiver::OnMessage, &logged_poses)))),
        caps(source->capabilities()),
        frame_q(static_cast<size_t>(cfg.queues.frames), QueuePolicy()),
        pose_q(static_cast<size_t>(cfg.queues.poses), QueuePolicy()),
        control_q(static_cast<size_t>(cfg.queues.controls), QueuePolicy()),
        intake(sys.model(), cfg.robot.control_stamp, cfg.lcm.controls_channel, &out, &control_q,
               &counters),
        logged_poses(cfg.lcm.pose_channel, cfg.replay.pose_sigma, &out, &pose_q, &counters),
        capture(std::make_unique<CaptureStage>(
            source.get(),
            CaptureOptions{cfg.lcm.frame_channel, cfg.lcm.publish_frames,
                           cfg.record.frame_encoding},
            &out, &frame_q, &counters, [this](const std::string& e) { SetSourceError(e); })),
        pose_stage(cfg.pose, cfg.detector, vis),
        preview(MakePreviewStage(cfg, vis, &out, caps.lossless)),
        detection(&pose_stage,
                  DetectionOptions{cfg.lcm.pose_channel, cfg.lcm.markers_channel,
                                   cfg.lcm.publish_markers, cfg.pose.sigma_px},
                  &out, &frame_q, &pose_q, &counters, preview.get()) {
    if (cfg.guidance.enabled) {
      guidance = std::make_unique<Guidance>(
          cfg.guidance,
          [this](int64_t utime, const kincal::guidance_t& m) {
            out.Publish(cfg.lcm.guidance_channel, utime, m);
          },
          /*background=*/!caps.lossless);
    }
  }

  // Live: fresh data matters more than old (drop the oldest); lossless: block.
  FullPolicy QueuePolicy() const {
    return caps.lossless ? FullPolicy::kBlock : FullPolicy::kDropOldest;
  }

  // ---- capture thread -----------------------------------------------------------------
  void CaptureLoop() {
    capture->Run(stop);
    source_done.store(true);
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

  void DetectionLoop() { detection.Run(); }

  // ---- filter thread ------------------------------------------------------------------
  FilterOutputs StageOutputs() {
    FilterOutputs o;
    o.params = [this](int64_t utime, const kincal::params_t& m) {
      std::lock_guard lock(filter_report_mu);
      filter_status = m.status;
      out.Publish(cfg.lcm.params_channel, utime, m);
    };
    o.model_check = [this](int64_t utime, const kincal::model_check_t& m) {
      {
        std::lock_guard lock(status_mu);
        model_check_evidence = m.evidence;
      }
      out.Publish(cfg.lcm.model_check_channel, utime, m);
    };
    o.estimate = [this](const Checkpoint& ck) {
      {
        std::lock_guard lock(status_mu);
        estimate = ck;
      }
      if (guidance) guidance->Offer(ck);
      if (drive) drive->Offer(ck);
    };
    o.calibration = [this](int64_t utime, const kincal::calibration_t& m, const Checkpoint* good) {
      if (good != nullptr) {
        std::lock_guard lock(status_mu);
        calibration = *good;
      }
      out.Publish(cfg.lcm.calibration_channel, utime, m);
    };
    o.checkpoint_due = [this] { WriteCheckpointLogged(); };
    return o;
  }

  void FilterLoop() {
    FilterStageOptions options = FilterStageOptionsFrom(cfg);
    options.lossless = caps.lossless;
    options.resumed = resume;
    FilterStage stage(
        sys, std::move(options), DaemonPrior(sys, cfg, resume),
        [this](ControlSample* c) { return control_q.TryPop(*c); }, StageOutputs(), &counters,
        std::make_unique<BatchWorker>(/*background=*/!caps.lossless));
    MergeInputs in;
    in.poses = &pose_q;
    in.controls = &control_q;
    in.controls_done = &controls_done;
    in.stop = &stop;
    in.lossless = caps.lossless;
    in.max_control_delay_ns = SecondsToNs(cfg.robot.max_control_delay_s);
    in.max_pending_poses = static_cast<size_t>(std::max(4 * cfg.queues.poses, kMinPendingPoses));
    {
      std::lock_guard lock(stage_mu);
      this->stage = &stage;
    }
    if (stop.load()) stage.CancelBatch();
    RunPoseControlMerge(&stage, in);
    {
      std::lock_guard lock(stage_mu);
      this->stage = nullptr;
    }
    filter_done.store(true);
  }

  // What a checkpoint and Estimate() give: the batch calibration once there is one.
  Checkpoint CalibrationLocked() const { return calibration ? *calibration : estimate; }

  void WriteCheckpointLogged() {
    Checkpoint ck;
    {
      std::lock_guard lock(status_mu);
      ck = CalibrationLocked();
    }
    if (ck.names.empty()) return;
    const Status written = WriteCheckpoint(cfg.checkpoint.path, ck);
    if (!written.ok()) spdlog::error("{}", written.message());
    std::lock_guard lock(status_mu);
    checkpoint_error = written.ok() ? "" : written.message();  // the last write counts
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
    s.since_last_frame_ns = MonotonicNs() - capture->last_frame_mono();
    s.expects_lcm_controls = !caps.carries_controls;
    s.controls_channel = cfg.lcm.controls_channel;
    if (out.recorder()) s.recorder_error = out.recorder()->error();
    const DetectionStage::Status det = detection.TakeStatus(/*reset_window=*/true);
    s.last_frame_error = det.last_frame_error;
    s.latency_p50_ms = det.window_p50_ms;
    s.latency_p99_ms = det.window_p99_ms;
    s.seconds_without_target = det.seconds_without_target;
    s.no_target_warn_s = cfg.no_target_warn_s;
    s.last_reject = intake.last_reject();
    {
      std::lock_guard lock(status_mu);
      s.source_error = source_error;
      s.model_check_evidence = model_check_evidence;
    }
    kincal::health_t h;
    std::lock_guard lock(filter_report_mu);
    s.filter_status = filter_status;
    health.Build(Snapshot(), s, period_s, RealtimeUtime(), &h);
    out.Publish(cfg.lcm.health_channel, h.utime, h);
    (void)health.Log(h.message, MonotonicNs());
  }

  // Every counter: the pipeline's own, and those the components keep.
  DaemonCounters Snapshot() const {
    DaemonCounters c = counters.Load();
    c.frames_dropped_device = source->device_drops();
    c.frames_dropped_queue = frame_q.dropped();
    c.frames_bad += source->rejected();
    c.poses_dropped_queue = pose_q.dropped();
    c.controls_dropped_queue = control_q.dropped();
    c.log_events_written = out.recorder() ? out.recorder()->written() : 0;
    c.log_events_lost = out.recorder() ? out.recorder()->lost() : 0;
    const ControlTiming timing = intake.timing();
    c.control_jitter_p95_ms = timing.jitter_p95_ms;
    c.control_jitter_max_ms = timing.jitter_max_ms;
    c.guidance_skipped_busy = guidance ? guidance->skipped_busy() : 0;
    c.drive_legs = drive ? drive->legs() : 0;
    c.drive_legs_failed = drive ? drive->legs_failed() : 0;
    c.preview_published = preview ? preview->published() : 0;
    c.preview_skipped = preview ? preview->skipped() : 0;
    return c;
  }
};

Daemon::Daemon(DaemonConfig config) {
  if (std::string error; !config.IsValid(&error)) throw StartupError("config: " + error);
  impl_ = std::make_unique<Impl>(std::move(config));
  Impl& d = *impl_;
  const DaemonConfig& cfg = d.cfg;
  d.resume = OrStartupError(ReadResumed(cfg, d.sys));
  // Outputs are locked before anything is written: a second daemon on the same path stops
  // here, and an unwritable folder shows now rather than at the first checkpoint.
  if (!cfg.record.path.empty()) {
    if (const Status s = d.record_lock.Acquire(cfg.record.path, "recording"); !s.ok())
      throw StartupError(s.message());
  }
  if (!cfg.checkpoint.path.empty()) {
    if (const Status s = d.checkpoint_lock.Acquire(cfg.checkpoint.path, "checkpoint"); !s.ok())
      throw StartupError(s.message());
  }
  const Status opened =
      d.out.Open(cfg.lcm, cfg.record, static_cast<size_t>(cfg.queues.recorder), d.caps.lossless);
  if (!opened.ok()) throw StartupError(opened.message());
  if (!d.caps.carries_controls) {
    d.out.lcm()->subscribeFunction(
        cfg.lcm.controls_channel,
        +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Impl* self) {
          // Receive stamp on the pipeline's time base (monotonic, mapped once): an NTP step of
          // the realtime clock does not make controls jump against frames.
          self->intake.OnMessage(rbuf->data, rbuf->data_size, PipelineUtime(MonotonicNs()));
        },
        &d);
  }
}

Daemon::~Daemon() = default;

StatusOr<std::unique_ptr<Daemon>> Daemon::Create(DaemonConfig config) {
  try {
    return std::unique_ptr<Daemon>(new Daemon(std::move(config)));
  } catch (const StartupError& e) {
    return Status::Error(e.what());
  }
}

void Daemon::Stop() { impl_->stop.store(true); }

int Daemon::Run() {
  Impl& d = *impl_;
  if (const Status started = d.source->Start(); !started.ok()) {
    spdlog::error("{}", started.message());
    d.SetSourceError(started.message());
    return 1;
  }
  d.capture->MarkStarted(MonotonicNs());
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
    while (!d.filter_done.load()) {  // a failed handle waits too, rather than spin
      if (!subscribe || d.out.lcm()->handleTimeout(50) < 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
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
      {
        std::lock_guard lock(d.stage_mu);
        if (d.stage != nullptr) d.stage->CancelBatch();
      }
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
  if (d.guidance) d.guidance->Drain();  // the last advice into the log
  if (d.preview) d.preview->Drain();    // the last preview into the log
  d.source->Stop();
  d.PublishHealth(period.count());
  d.out.CloseLog();
  EndOfRun end;
  end.checkpoint_path = d.cfg.checkpoint.path;
  end.last_reject = d.intake.last_reject();
  end.source_ended = d.source_done.load() && !stopping;
  end.counters = counters();
  spdlog::info("kincald: {}", SummaryLine(end.counters));
  std::lock_guard lock(d.status_mu);
  end.checkpoint_error = d.checkpoint_error;
  end.source_error = d.source_error;
  end.has_estimate = !d.CalibrationLocked().names.empty();
  return EndOfRunCode(end);
}

Checkpoint Daemon::Estimate() const {
  std::lock_guard lock(impl_->status_mu);
  return impl_->CalibrationLocked();
}

Checkpoint Daemon::FilterEstimate() const {
  std::lock_guard lock(impl_->status_mu);
  return impl_->estimate;
}

DaemonCounters Daemon::counters() const {
  DaemonCounters c = impl_->Snapshot();
  const DetectionStage::Status det = impl_->detection.TakeStatus(/*reset_window=*/false);
  c.latency_p50_ms = det.total_p50_ms;
  c.latency_p99_ms = det.total_p99_ms;
  c.latency_max_ms = det.total_max_ms;
  return c;  // control jitter: from Snapshot()
}

}  // namespace kincal::daemon
