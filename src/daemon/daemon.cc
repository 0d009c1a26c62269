// kincald pipeline: threads, queues, LCM I/O, filter, health.
#include "kincal/daemon/daemon.h"

#include <kincal/controls_t.hpp>
#include <kincal/frame_t.hpp>
#include <kincal/health_t.hpp>
#include <kincal/markers_t.hpp>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <limits>
#include <optional>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "kincal/analysis/model_check.h"
#include "kincal/angles.h"
#include "kincal/daemon/bounded_queue.h"
#include "kincal/daemon/lcm_guard.h"
#include "kincal/daemon/pose_stage.h"
#include "kincal/daemon/recorder.h"
#include "kincal/daemon/sources.h"
#include "kincal/estimation/online_calibrator.h"
#include "kincal/scenario.h"
#include "kincal/system.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/pose.h"

namespace kincal::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// Latency histogram: 10 us bins up to 200 ms (beyond: the last bin). Fixed size.
class LatencyHistogram {
 public:
  void Add(double ms) {
    const int bin = std::clamp(static_cast<int>(ms * 100.0), 0, kBins - 1);
    ++bins_[static_cast<size_t>(bin)];
    ++count_;
    max_ms_ = std::max(max_ms_, ms);
  }
  double Percentile(double p) const {
    if (count_ == 0) return 0.0;
    const int64_t want = static_cast<int64_t>(std::ceil(p * static_cast<double>(count_)));
    int64_t seen = 0;
    for (int i = 0; i < kBins; ++i) {
      seen += bins_[static_cast<size_t>(i)];
      if (seen >= want) return (i + 1) * 0.01;
    }
    return kBins * 0.01;
  }
  double max_ms() const { return max_ms_; }
  int64_t count() const { return count_; }
  void Reset() { *this = LatencyHistogram(); }

 private:
  static constexpr int kBins = 20000;
  std::array<int64_t, kBins> bins_{};
  int64_t count_ = 0;
  double max_ms_ = 0.0;
};

// Fixed-capacity FIFO used by the filter thread to hold poses waiting for controls.
class PoseRing {
 public:
  explicit PoseRing(size_t capacity) : items_(capacity) {}
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == items_.size(); }
  PoseSample& front() { return items_[head_]; }
  void push(const PoseSample& p) {
    items_[(head_ + size_) % items_.size()] = p;
    ++size_;
  }
  void pop() {
    head_ = (head_ + 1) % items_.size();
    --size_;
  }

 private:
  std::vector<PoseSample> items_;
  size_t head_ = 0, size_ = 0;
};

}  // namespace

struct Daemon::Impl {
  DaemonConfig cfg;
  System sys;
  VisionSetup vis;
  bool lossless;
  FullPolicy live_policy;

  std::unique_ptr<lcm::LCM> lcm;
  std::mutex lcm_mu;
  std::unique_ptr<Recorder> recorder;
  std::unique_ptr<FrameSource> source;

  BoundedQueue<Frame> frame_q;
  BoundedQueue<PoseSample> pose_q;
  BoundedQueue<ControlSample> control_q;

  std::atomic<bool> stop{false};
  std::atomic<bool> source_done{false};
  std::atomic<bool> controls_done{false};
  std::atomic<bool> filter_done{false};
  std::string source_error;
  std::mutex status_mu;  // guards source_error, estimate, latency
  std::string last_frame_error;

  // Counters (atomics: written by one thread each, read by health).
  std::atomic<int64_t> frames_captured{0}, frame_errors{0}, poses_valid{0}, poses_invalid{0},
      poses_stale{0}, poses_gated{0}, updates{0}, run_resets{0}, controls_received{0},
      controls_rejected{0}, controls_out_of_order{0}, poses_published{0};
  std::atomic<int64_t> last_frame_mono{0}, last_control_mono{0};
  LatencyHistogram latency_total, latency_window;
  Checkpoint estimate;
  std::optional<Checkpoint> resume;

  explicit Impl(DaemonConfig c)
      : cfg(std::move(c)),
        sys(MakeSystem(cfg.robot.model, cfg.robot.effects)),
        vis(LoadVisionSetup(cfg)),
        lossless((cfg.source == "replay" && cfg.replay.speed <= 0) || (cfg.source == "sim" && cfg.sim.speed <= 0)),
        live_policy(lossless ? FullPolicy::kBlock : FullPolicy::kDropOldest),
        frame_q(static_cast<size_t>(cfg.queues.frames), live_policy),
        pose_q(static_cast<size_t>(cfg.queues.poses), live_policy),
        control_q(static_cast<size_t>(cfg.queues.controls), live_policy) {}

  int64_t Now() const { return RealtimeUtime(); }
  // Controls come over LCM (a real robot, or the simulated one told to use LCM).
  bool subscribes() const {
    return cfg.source == "v4l2" || cfg.source == "libcamera" || (cfg.source == "sim" && cfg.sim.controls_via_lcm);
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
    thread_local kincal::controls_t m;
    if (recorder) recorder->Write(cfg.lcm.controls_channel, receive_utime, data, n);
    std::string why;
    if (n > (1u << 20) || !PlausibleControls(data, n, kMaxControls, &why) ||
        m.decode(data, 0, static_cast<int>(n)) < 0 || m.num_controls < 0 ||
        m.num_controls > kMaxControls || m.model != sys.model().name()) {
      controls_rejected.fetch_add(1);
      return;
    }
    ControlSample s;
    s.receive_utime = receive_utime;
    s.sender_utime = m.sender_utime;
    s.utime = cfg.robot.control_stamp == "sender" ? m.sender_utime : receive_utime;
    std::array<bool, kMaxControls> seen{};
    for (int i = 0; i < m.num_controls; ++i) {
      const int k = sys.model().ControlIndex(m.names[static_cast<size_t>(i)]);
      const double v = m.values[static_cast<size_t>(i)];
      if (k < 0 || !std::isfinite(v)) {
        controls_rejected.fetch_add(1);
        return;
      }
      s.values[static_cast<size_t>(k)] = v;
      seen[static_cast<size_t>(k)] = true;
    }
    for (int k = 0; k < sys.num_controls(); ++k) {
      if (!seen[static_cast<size_t>(k)]) {
        controls_rejected.fetch_add(1);
        return;
      }
    }
    controls_received.fetch_add(1);
    last_control_mono.store(MonotonicNs());
    control_q.Push(s);
  }

  // ---- capture thread -----------------------------------------------------------------
  void CaptureLoop() {
    Frame f;
    thread_local kincal::frame_t msg;
    std::vector<uint8_t> png;
    while (!stop.load()) {
      std::string error;
      const SourceStatus st = source->Next(&f, 100, &error);
      if (st == SourceStatus::kEnd) break;
      if (st == SourceStatus::kTimeout) continue;
      if (st == SourceStatus::kError) {
        std::lock_guard lock(status_mu);
        source_error = error;
        spdlog::error("source {}: {}", source->name(), error);
        break;
      }
      frames_captured.fetch_add(1);
      last_frame_mono.store(MonotonicNs());
      if (recorder || cfg.lcm.publish_frames) {
        msg.schema_version = 1;
        msg.utime = f.utime;
        msg.device_utime = f.device_utime;
        msg.sequence = f.sequence;
        msg.width = f.width;
        msg.height = f.height;
        msg.stride = f.stride;
        if (cfg.record.frame_encoding == "png" && f.format == PixelFormat::kGrey) {
          cv::Mat grey;
          ToGrey(f, &grey);
          cv::imencode(".png", grey, png);
          msg.pixel_format = "PNG";
          msg.data.assign(png.begin(), png.end());
        } else {
          msg.pixel_format = std::string(PixelFormatName(f.format));
          msg.data.resize(f.data.size());
          std::memcpy(msg.data.data(), f.data.data(), f.data.size());
        }
        msg.size = static_cast<int32_t>(msg.data.size());
        Publish(cfg.lcm.frame_channel, f.utime, msg, cfg.lcm.publish_frames);
      }
      frame_q.Push(f);
    }
    source_done.store(true);
    frame_q.Close();
    if (cfg.source == "replay" || (cfg.source == "sim" && !cfg.sim.controls_via_lcm)) {
      controls_done.store(true);  // the source carried the controls: there are no more
    } else if (cfg.source == "sim") {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let LCM deliver the last ones
      controls_done.store(true);
    }
  }

  // ---- detection / pose thread --------------------------------------------------------
  void DetectionLoop() {
    PoseStage stage(cfg, vis);
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
        frame_errors.fetch_add(1);
        std::lock_guard lock(status_mu);
        last_frame_error = error;
        continue;
      }
      (p.valid ? poses_valid : poses_invalid).fetch_add(1);
      // Publish the pose (and markers) now: this is the frame-to-publish latency.
      pose_msg.schema_version = 1;
      pose_msg.utime = p.utime;
      pose_msg.source_utime = p.device_utime;
      pose_msg.target_id = 0;
      pose_msg.x = p.xytheta.x();
      pose_msg.y = p.xytheta.y();
      pose_msg.theta = p.xytheta.z();
      for (int i = 0; i < 9; ++i) pose_msg.covariance[i] = p.covariance(i / 3, i % 3);
      pose_msg.reprojection_rms_px = p.rms_px;
      pose_msg.valid = p.valid ? 1 : 0;
      Publish(cfg.lcm.pose_channel, p.utime, pose_msg);
      poses_published.fetch_add(1);
      if (cfg.lcm.publish_markers) {
        markers_msg.schema_version = 1;
        markers_msg.utime = p.utime;
        markers_msg.frame_sequence = p.sequence;
        markers_msg.num_markers = p.num_markers;
        const size_t n = static_cast<size_t>(p.num_markers);
        markers_msg.u.assign(p.u.begin(), p.u.begin() + static_cast<long>(n));
        markers_msg.v.assign(p.v.begin(), p.v.begin() + static_cast<long>(n));
        markers_msg.sigma_px.assign(n, cfg.pose.sigma_px);
        markers_msg.id.assign(p.id.begin(), p.id.begin() + static_cast<long>(n));
        markers_msg.target_id.assign(n, 0);
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
  void FilterLoop() {
    std::unique_ptr<OnlineCalibrator> cal;
    std::unique_ptr<ModelCheck> check;
    PoseRing pending(static_cast<size_t>(std::max(4 * cfg.queues.poses, 256)));
    PoseSample p;
    ControlSample c;
    int64_t max_control_utime = INT64_MIN;
    int64_t last_pose_utime = 0;
    // "Long ago" without overflow in the differences below.
    constexpr int64_t kLongAgo = std::numeric_limits<int64_t>::min() / 4;
    int64_t last_params_utime = kLongAgo, last_check_utime = kLongAgo, last_checkpoint_utime = 0;
    kincal::params_t params_msg{};
    const int np = sys.num_params();
    // The prior: a checkpoint to resume from, or the configured guess.
    VecN<kMaxState> prior = ParamsFrom(sys, cfg.robot.guess, cfg.file + ": robot.guess");
    StateMat prior_cov = StateMat::Zero(np, np);
    for (int i = 0; i < np; ++i) {
      const double s = cfg.robot.guess_sigma_fraction *
                       std::max(std::abs(prior[i]), sys.params()[static_cast<size_t>(i)].default_sigma);
      prior_cov(i, i) = s * s;
    }
    if (resume) ApplyResume(*resume, &prior, &prior_cov);
    const Eigen::VectorXd prior_sigma = prior_cov.diagonal().cwiseSqrt();
    OnlineCalibratorOptions opt;
    opt.filter = cfg.filter.type;
    opt.noise.control_psd = cfg.filter.control_psd.empty() ? std::vector<double>(static_cast<size_t>(sys.num_controls()), 0.0)
                                                           : cfg.filter.control_psd;
    opt.noise.pose_psd = Eigen::Vector3d(cfg.filter.pose_psd[0], cfg.filter.pose_psd[1], cfg.filter.pose_psd[2]);
    const int64_t max_delay_ns = SecondsToNs(cfg.robot.max_control_delay_s);
    const int64_t max_gap_us = static_cast<int64_t>(cfg.filter.max_pose_gap_s * 1e6);
    const int64_t params_every_us = cfg.filter.params_rate_hz > 0 ? static_cast<int64_t>(1e6 / cfg.filter.params_rate_hz) : 0;
    const int64_t check_every_us = static_cast<int64_t>(1e6 / cfg.health_rate_hz);
    const int64_t checkpoint_every_us = static_cast<int64_t>(cfg.checkpoint.every_s * 1e6);

    auto drain_controls = [&] {
      while (control_q.TryPop(c)) {
        if (!cal) {
          cal = std::make_unique<OnlineCalibrator>(sys, opt, c.utime * 1000);
          check = std::make_unique<ModelCheck>(sys);
        }
        if (!cal->AddControl(c.utime * 1000, std::span<const double>(c.values.data(), static_cast<size_t>(sys.num_controls())))) {
          controls_out_of_order.fetch_add(1);
          continue;
        }
        max_control_utime = std::max(max_control_utime, c.utime);
      }
    };
    auto publish_params = [&](int64_t utime, bool force) {
      if (!cal || !cal->initialized()) return;
      if (!force && utime - last_params_utime < params_every_us) return;
      last_params_utime = utime;
      const auto mean = cal->params();
      const auto C = cal->params_covariance();
      params_msg.schema_version = 1;
      params_msg.utime = utime;
      params_msg.model = std::string(sys.model().name());
      params_msg.estimator = std::string(cal->filter_name());
      params_msg.num_params = np;
      params_msg.names.resize(static_cast<size_t>(np));
      params_msg.units.resize(static_cast<size_t>(np));
      params_msg.values.resize(static_cast<size_t>(np));
      params_msg.sigmas.resize(static_cast<size_t>(np));
      params_msg.covariance.resize(static_cast<size_t>(np));
      bool converged = true;
      for (int i = 0; i < np; ++i) {
        const auto& info = sys.params()[static_cast<size_t>(i)];
        params_msg.names[static_cast<size_t>(i)] = info.name;
        params_msg.units[static_cast<size_t>(i)] = info.unit;
        params_msg.values[static_cast<size_t>(i)] = mean[i];
        params_msg.sigmas[static_cast<size_t>(i)] = std::sqrt(std::max(0.0, C(i, i)));
        params_msg.covariance[static_cast<size_t>(i)].resize(static_cast<size_t>(np));
        for (int k = 0; k < np; ++k) params_msg.covariance[static_cast<size_t>(i)][static_cast<size_t>(k)] = C(i, k);
        converged = converged && params_msg.sigmas[static_cast<size_t>(i)] < 0.05 * prior_sigma[i];
      }
      params_msg.update_count = cal->update_count();
      const auto verdict = check->Verdict();
      params_msg.status = verdict.window >= 100 && verdict.nis_mean > 10 * verdict.nis_expected
                              ? kincal::params_t::STATUS_DIVERGED
                              : (converged ? kincal::params_t::STATUS_CONVERGED : kincal::params_t::STATUS_CONVERGING);
      Publish(cfg.lcm.params_channel, utime, params_msg);
      std::lock_guard lock(status_mu);
      estimate.model = std::string(sys.model().name());
      estimate.effects = cfg.robot.effects;
      estimate.filter = std::string(cal->filter_name());
      estimate.utime = utime;
      estimate.update_count = cal->update_count();
      estimate.names = params_msg.names;
      estimate.units = params_msg.units;
      estimate.values = params_msg.values;
      estimate.covariance = C.topLeftCorner(np, np);
    };
    auto process = [&](const PoseSample& ps) {
      if (!ps.valid) return;
      if (!cal || max_control_utime == INT64_MIN) return;  // no controls yet: nothing to propagate with
      const TimeNs t = ps.utime * 1000;
      if (!cal->initialized()) {
        cal->Initialize(t, ps.xytheta, ps.covariance, prior, prior_cov);
      } else if (t <= cal->time_ns()) {
        poses_stale.fetch_add(1);
        return;
      } else if (ps.utime - last_pose_utime > max_gap_us) {
        cal->ResetPose(t, ps.xytheta, ps.covariance);
        run_resets.fetch_add(1);
      } else {
        const UpdateResult r = cal->AddPose(t, ps.xytheta, ps.covariance);
        if (r.ok) {
          updates.fetch_add(1);
          check->Add(t, r, cal->state(), cal->controls());
        }
      }
      last_pose_utime = ps.utime;
      cal->controls().DiscardBefore(cal->controls().ToSeconds(t) - cfg.filter.control_history_s);
      publish_params(ps.utime, false);
      if (ps.utime - last_check_utime >= check_every_us) {
        last_check_utime = ps.utime;
        Publish(cfg.lcm.model_check_channel, ps.utime, ToMessage(check->Verdict(), std::string(sys.model().name()), ps.utime));
      }
      if (!cfg.checkpoint.path.empty() && ps.utime - last_checkpoint_utime >= checkpoint_every_us) {
        last_checkpoint_utime = ps.utime;
        WriteCheckpointLogged();
      }
    };

    while (true) {
      const bool got = pose_q.Pop(p, std::chrono::milliseconds(20));
      drain_controls();
      if (got) {
        if (pending.full()) {  // hold no more: use the oldest with what we have
          process(pending.front());
          pending.pop();
        }
        pending.push(p);
      }
      const bool poses_over = !got && pose_q.closed_and_empty();
      const bool no_more_controls = controls_done.load() && control_q.size() == 0;
      if (no_more_controls) drain_controls();
      // A pose is processed once the controls up to its time are in, or the controls
      // stream has ended, or (live) it has waited max_control_delay_s.
      while (!pending.empty()) {
        const PoseSample& f = pending.front();
        const bool controls_in = max_control_utime >= f.utime;
        const bool waited = !lossless && MonotonicNs() - f.arrival_mono_ns > max_delay_ns;
        if (!(controls_in || no_more_controls || (poses_over && stop.load()) || waited)) break;
        process(f);
        pending.pop();
      }
      if (poses_over && (no_more_controls || stop.load() || !lossless)) {
        drain_controls();
        while (!pending.empty()) {
          process(pending.front());
          pending.pop();
        }
        break;
      }
    }
    if (cal && cal->initialized()) {
      publish_params(last_pose_utime, true);
      if (!cfg.checkpoint.path.empty()) WriteCheckpointLogged();
    }
    filter_done.store(true);
  }

  void ApplyResume(const Checkpoint& ck, VecN<kMaxState>* prior, StateMat* prior_cov) {
    // Parameters are matched by name; any the checkpoint lacks keep the configured prior.
    int matched = 0;
    for (size_t i = 0; i < ck.names.size(); ++i) {
      const int a = sys.ParamIndex(ck.names[i]);
      if (a < 0) continue;
      ++matched;
      (*prior)[a] = ck.values[i];
      for (size_t k = 0; k < ck.names.size(); ++k) {
        const int b = sys.ParamIndex(ck.names[k]);
        if (b >= 0) (*prior_cov)(a, b) = ck.covariance(static_cast<int>(i), static_cast<int>(k));
      }
    }
    spdlog::info("resumed {} of {} parameters from {} ({} updates)", matched, sys.num_params(), cfg.checkpoint.resume,
                 ck.update_count);
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
  void PublishHealth(double period_s, DaemonCounters* prev) {
    const DaemonCounters now = Counters();
    kincal::health_t h{};
    h.schema_version = 1;
    h.utime = Now();
    h.source = source->name();
    h.frame_rate_hz = static_cast<double>(now.frames_captured - prev->frames_captured) / period_s;
    h.frames_captured = now.frames_captured;
    h.frames_dropped_device = now.frames_dropped_device;
    h.frames_dropped_queue = now.frames_dropped_queue;
    h.poses_published = poses_published.load();
    h.controls_received = now.controls_received;
    h.messages_rejected = now.controls_rejected;
    h.log_events_written = now.log_events_written;
    h.log_events_lost = now.log_events_lost;
    {
      std::lock_guard lock(status_mu);
      h.latency_p50_ms = latency_window.Percentile(0.5);
      h.latency_p99_ms = latency_window.Percentile(0.99);
      latency_window.Reset();
    }
    std::string problems;
    auto add = [&](const std::string& s) { problems += (problems.empty() ? "" : "; ") + s; };
    {
      std::lock_guard lock(status_mu);
      if (!source_error.empty()) add("source: " + source_error);
      if (now.frame_errors > prev->frame_errors) add("bad frames: " + last_frame_error);
    }
    const TimeNs mono = MonotonicNs();
    if (!source_done.load() && mono - last_frame_mono.load() > 2 * kNsPerSecond) add("no frames for 2 s");
    if (now.frames_dropped_queue > prev->frames_dropped_queue) add("frame queue full: detection is too slow");
    if (now.frames_dropped_device > prev->frames_dropped_device) add("the device dropped frames");
    if (now.log_events_lost > prev->log_events_lost) add("log events lost");
    if (now.controls_rejected > prev->controls_rejected) add("rejected control messages");
    if (!cfg.record.path.empty() && recorder && !recorder->error().empty()) add(recorder->error());
    if (subscribes() && now.controls_received == 0 && now.frames_captured > 0) {
      add("no controls received on " + cfg.lcm.controls_channel);
    }
    h.ok = problems.empty() ? 1 : 0;
    h.message = problems;
    Publish(cfg.lcm.health_channel, h.utime, h);
    if (!problems.empty()) spdlog::warn("health: {}", problems);
    *prev = now;
  }

  DaemonCounters Counters() const {
    DaemonCounters d;
    d.frames_captured = frames_captured.load();
    d.frames_dropped_device = source ? source->device_drops() : 0;
    d.frames_dropped_queue = frame_q.dropped();
    d.frame_errors = frame_errors.load() + (source ? source->rejected() : 0);
    d.poses_valid = poses_valid.load();
    d.poses_invalid = poses_invalid.load();
    d.poses_dropped_queue = pose_q.dropped();
    d.poses_stale = poses_stale.load();
    d.poses_gated = poses_gated.load();
    d.updates = updates.load();
    d.run_resets = run_resets.load();
    d.controls_received = controls_received.load();
    d.controls_rejected = controls_rejected.load();
    d.controls_out_of_order = controls_out_of_order.load();
    d.controls_dropped_queue = control_q.dropped();
    d.log_events_written = recorder ? recorder->written() : 0;
    d.log_events_lost = recorder ? recorder->lost() : 0;
    return d;
  }
};

Daemon::Daemon(DaemonConfig config) {
  Validate(config);
  impl_ = std::make_unique<Impl>(std::move(config));
  Impl& d = *impl_;
  DaemonConfig& cfg = d.cfg;
  if (!cfg.checkpoint.resume.empty()) {
    d.resume = ReadCheckpoint(cfg.checkpoint.resume);
    if (d.resume->model != d.sys.model().name()) {
      throw std::runtime_error(cfg.checkpoint.resume + ": checkpoint is for model '" + d.resume->model +
                               "', the config says '" + std::string(d.sys.model().name()) + "'");
    }
  }
  d.lcm = std::make_unique<lcm::LCM>(cfg.lcm.url);
  if (!d.lcm->good()) {
    throw std::runtime_error("LCM: cannot open '" + (cfg.lcm.url.empty() ? std::string("default URL") : cfg.lcm.url) +
                             "' (for udpm on loopback: `ip link set lo multicast on` and a 224.0.0.0/4 route)");
  }
  if (!cfg.record.path.empty()) {
    d.recorder = std::make_unique<Recorder>(cfg.record.path, static_cast<size_t>(cfg.queues.recorder),
                                            d.lossless ? FullPolicy::kBlock : FullPolicy::kDropNewest,
                                            cfg.record.flush_every_s);
  }
  auto intake = [&d](const void* data, size_t n, int64_t utime) { d.OnControls(data, n, utime); };
  if (cfg.source == "sim") {
    d.source = MakeSimSource(cfg, d.vis, intake,
                             [&d](const std::string& ch, const void* data, size_t n) { d.PublishRaw(ch, data, n); });
  } else if (cfg.source == "replay") {
    d.source = MakeReplaySource(cfg, intake);
  } else if (cfg.source == "v4l2") {
    d.source = MakeV4l2Source(cfg.v4l2);
  } else {
    d.source = MakeLibcameraSource(cfg.libcamera);
  }
  if (d.subscribes()) {
    d.lcm->subscribeFunction(
        cfg.lcm.controls_channel,
        +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Impl* self) {
          self->OnControls(rbuf->data, rbuf->data_size, rbuf->recv_utime);
        },
        &d);
  }
}

Daemon::~Daemon() = default;

void Daemon::Stop() { impl_->stop.store(true); }

int Daemon::Run() {
  Impl& d = *impl_;
  d.source->Start();
  d.last_frame_mono.store(MonotonicNs());
  spdlog::info("kincald: source {}, model {}{}, filter {}, LCM {}{}", d.source->name(), d.cfg.robot.model,
               d.cfg.robot.effects.empty() ? "" : " + effects", d.cfg.filter.type,
               d.cfg.lcm.url.empty() ? "default" : d.cfg.lcm.url,
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
  const bool subscribe = d.subscribes();
  std::thread lcm_thread([&d, subscribe] {
    while (!d.filter_done.load()) {
      if (subscribe) {
        d.lcm->handleTimeout(50);
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  });
  DaemonCounters prev;
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
      d.PublishHealth(period.count(), &prev);
      next_health += std::chrono::duration_cast<Clock::duration>(period);
    }
  }
  capture.join();
  detection.join();
  filter.join();
  lcm_thread.join();
  d.source->Stop();
  d.PublishHealth(period.count(), &prev);
  if (d.recorder) d.recorder->Close();
  const DaemonCounters c = counters();
  spdlog::info(
      "kincald: {} frames ({} dropped by the device, {} by the queue, {} bad), {} valid poses, {} updates, {} runs, "
      "{} controls ({} rejected, {} out of order), log {} written / {} lost, latency p50 {:.3f} ms p99 {:.3f} ms",
      c.frames_captured, c.frames_dropped_device, c.frames_dropped_queue, c.frame_errors, c.poses_valid, c.updates,
      c.run_resets + (c.updates > 0 ? 1 : 0), c.controls_received, c.controls_rejected, c.controls_out_of_order,
      c.log_events_written, c.log_events_lost, c.latency_p50_ms, c.latency_p99_ms);
  std::lock_guard lock(d.status_mu);
  return d.source_error.empty() ? 0 : 1;
}

Checkpoint Daemon::Estimate() const {
  std::lock_guard lock(impl_->status_mu);
  return impl_->estimate;
}

DaemonCounters Daemon::counters() const {
  DaemonCounters c = impl_->Counters();
  std::lock_guard lock(impl_->status_mu);
  c.latency_p50_ms = impl_->latency_total.Percentile(0.5);
  c.latency_p99_ms = impl_->latency_total.Percentile(0.99);
  c.latency_max_ms = impl_->latency_total.max_ms();
  return c;
}

}  // namespace kincal::daemon
