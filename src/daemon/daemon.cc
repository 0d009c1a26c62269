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
#include "kincal/daemon/control_input.h"
#include "kincal/daemon/pose_stage.h"
#include "kincal/daemon/recorder.h"
#include "kincal/daemon/sources.h"
#include "kincal/estimation/batch.h"
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
  size_t size() const { return size_; }
  const PoseSample& at(size_t k) const { return items_[(head_ + k) % items_.size()]; }
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
  std::string last_reject;

  // Counters (atomics: written by one thread each, read by health).
  std::atomic<int64_t> frames_captured{0}, frame_errors{0}, poses_valid{0}, poses_invalid{0},
      poses_gated{0}, updates{0}, run_resets{0}, controls_received{0},
      controls_rejected{0}, controls_out_of_order{0}, poses_published{0}, frames_out_of_order{0},
      controls_late{0}, filter_resets{0}, time_resets{0}, source_restarts{0}, discarded_at_reset{0};
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
    if (recorder) recorder->Write(cfg.lcm.controls_channel, receive_utime, data, n);
    ControlSample s;
    thread_local std::string why;
    if (!DecodeControls(data, n, sys.model(), cfg.robot.control_stamp == "sender", receive_utime, &s, &why)) {
      if (controls_rejected.fetch_add(1) == 0) spdlog::warn("rejected a control message: {}", why);
      std::lock_guard lock(status_mu);
      last_reject = why;
      return;
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
        {
          std::lock_guard lock(status_mu);
          source_error = error;
        }
        spdlog::error("source {}: {}", source->name(), error);
        if (cfg.source != "v4l2" && cfg.source != "libcamera") break;
        if (!ReopenWithBackoff()) break;  // stopped while waiting
        continue;
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

  // A live device failed: close it and open it again, waiting 0.25 s, 0.5 s, ... up to 5 s
  // between attempts, until it is back or the daemon is stopped. Health says so meanwhile.
  bool ReopenWithBackoff() {
    double wait_s = 0.25;
    while (!stop.load()) {
      const TimeNs until = MonotonicNs() + SecondsToNs(wait_s);
      while (!stop.load() && MonotonicNs() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (stop.load()) return false;
      std::string error;
      if (source->Reopen(&error)) {
        source_restarts.fetch_add(1);
        {
          std::lock_guard lock(status_mu);
          source_error.clear();
        }
        spdlog::info("source {}: reopened, capturing again", source->name());
        return true;
      }
      {
        std::lock_guard lock(status_mu);
        source_error = error + " (retrying every " + std::to_string(std::min(5.0, 2 * wait_s)).substr(0, 4) + " s)";
      }
      wait_s = std::min(5.0, 2 * wait_s);
    }
    return false;
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
    // Recent poses the filter used, for a batch re-fit when it diverges.
    PoseRing recent(static_cast<size_t>(4096));
    PoseSample p;
    ControlSample c;
    constexpr int64_t kNever = std::numeric_limits<int64_t>::min() / 4;  // no overflow in differences
    int64_t max_control_utime = kNever;
    int64_t last_pose_utime = kNever;
    int64_t last_params_utime = kNever, last_check_utime = kNever, last_checkpoint_utime = 0;
    int consecutive_gated = 0;
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
    const int64_t batch_window_us = static_cast<int64_t>(cfg.filter.batch_window_s * 1e6);

    // A clock jumped back: start a new time base. Parameters and their covariance carry
    // over as the prior; the control history and the pose are dropped. Events of the other
    // stream still stamped on the old time base (later than the jump's new time by more
    // than max_pose_gap_s) are discarded until that stream shows a new-base stamp.
    int64_t horizon = kNever;  // kNever: no reset in progress
    bool controls_rebased = true, poses_rebased = true;
    auto reset_time_base = [&](const char* what, int64_t new_utime, bool by_controls) {
      if (cal && cal->initialized()) {
        prior.head(np) = cal->params().head(np);
        prior_cov = cal->params_covariance();
      }
      cal.reset();
      check.reset();
      max_control_utime = kNever;
      last_pose_utime = kNever;
      while (!recent.empty()) recent.pop();
      horizon = new_utime + max_gap_us;
      controls_rebased = by_controls;
      poses_rebased = !by_controls;
      time_resets.fetch_add(1);
      spdlog::warn("{} jumped back by more than filter.max_pose_gap_s: new time base, parameters kept", what);
    };
    // True if the event belongs to a time base that was just left.
    auto from_old_base = [&](int64_t utime, bool* rebased) {
      if (horizon == kNever || *rebased) return false;
      if (utime > horizon) {
        discarded_at_reset.fetch_add(1);
        return true;
      }
      *rebased = true;
      if (controls_rebased && poses_rebased) horizon = kNever;
      return false;
    };
    // A control stamped well before the newest one: the control clock jumped back. It is
    // held (with the controls behind it) until the poses show the jump too, so that every
    // pose of the old time base is used first whatever the threads' timing; if they do not
    // (the pose stream ends, or live, a second passes), the controls alone start the new base.
    std::optional<ControlSample> held_jump;
    TimeNs held_since_mono = 0;
    auto add_control = [&](const ControlSample& cs) {
      if (!cal) {
        cal = std::make_unique<OnlineCalibrator>(sys, opt, cs.utime * 1000);
        check = std::make_unique<ModelCheck>(sys);
      }
      if (cal->initialized() && cs.utime * 1000 < cal->time_ns()) controls_late.fetch_add(1);
      if (!cal->AddControl(cs.utime * 1000, std::span<const double>(cs.values.data(), static_cast<size_t>(sys.num_controls())))) {
        controls_out_of_order.fetch_add(1);
        return;
      }
      max_control_utime = std::max(max_control_utime, cs.utime);
    };
    auto drain_controls = [&] {
      while (!held_jump && control_q.TryPop(c)) {
        if (from_old_base(c.utime, &controls_rebased)) continue;
        if (max_control_utime != kNever && c.utime < max_control_utime - max_gap_us) {
          held_jump = c;
          held_since_mono = MonotonicNs();
          break;
        }
        add_control(c);
      }
    };
    // Starts the new time base at a jump (seen in the poses at `utime`, or in the controls).
    auto take_jump = [&](const char* what, int64_t utime, bool by_controls) {
      reset_time_base(what, utime, by_controls);
      if (held_jump) {
        controls_rebased = true;
        if (poses_rebased) horizon = kNever;
        add_control(*held_jump);
        held_jump.reset();
      }
      drain_controls();
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
      params_msg.status = (verdict.window >= 100 && verdict.nis_mean > 10 * verdict.nis_expected) || consecutive_gated > 0
                              ? kincal::params_t::STATUS_DIVERGED
                              : (converged ? kincal::params_t::STATUS_CONVERGED : kincal::params_t::STATUS_CONVERGING);
      if (consecutive_gated > 0 && consecutive_gated < cfg.filter.divergence_gated) params_msg.status = kincal::params_t::STATUS_CONVERGING;
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
    // Divergence: the filter has rejected divergence_gated poses in a row. Re-fit the
    // parameters by batch (robust loss) over the recent poses and controls, and start the
    // filter again from that estimate (or from the prior if the fit fails).
    auto recover = [&](const PoseSample& ps) {
      std::vector<PoseMeasurement> meas;
      int segment = 0;
      int64_t prev = kNever;
      for (size_t k = 0; k < recent.size(); ++k) {
        const PoseSample& r = recent.at(k);
        if (r.utime < ps.utime - batch_window_us) continue;
        if (prev != kNever && r.utime - prev > max_gap_us) ++segment;
        prev = r.utime;
        meas.push_back({r.utime * 1000, r.xytheta, r.covariance, segment});
      }
      VecN<kMaxState> start = cal->params();
      StateMat start_cov = prior_cov;
      std::string how = "the configured prior";
      if (meas.size() >= 10) {
        BatchOptions bo;
        bo.huber_scale = 2.0;
        bo.max_iterations = 50;
        bo.warmup_s = 0.0;
        try {
          const BatchResult br = FitBatch(sys, cal->controls(), meas, prior.head(np), bo);
          if (br.params.allFinite() && br.covariance.rows() == np && br.covariance.allFinite()) {
            start.head(np) = br.params;
            start_cov = 4.0 * br.covariance;  // a margin: the window was short and had outliers
            how = "a batch fit over " + std::to_string(meas.size()) + " poses";
          }
        } catch (const std::exception& e) {
          spdlog::warn("batch re-fit failed: {}", e.what());
        }
      }
      if (how == "the configured prior") start = prior;
      auto fresh = std::make_unique<OnlineCalibrator>(sys, opt, cal->controls().origin_ns());
      fresh->controls() = cal->controls();
      fresh->Initialize(ps.utime * 1000, ps.xytheta, ps.covariance, start, start_cov);
      cal = std::move(fresh);
      check->Reset();
      consecutive_gated = 0;
      filter_resets.fetch_add(1);
      spdlog::warn("filter diverged ({} poses in a row failed the innovation gate): restarted from {}",
                   cfg.filter.divergence_gated, how);
    };
    auto process = [&](const PoseSample& ps) {
      if (!ps.valid) return;
      if (from_old_base(ps.utime, &poses_rebased)) return;
      if (last_pose_utime != kNever && ps.utime < last_pose_utime - max_gap_us) {
        take_jump(held_jump ? "the camera and control clocks" : "the camera clock", ps.utime, false);
      }
      if (!cal || max_control_utime == kNever) return;  // no controls yet: nothing to propagate with
      const TimeNs t = ps.utime * 1000;
      if (!cal->initialized()) {
        // Start only where the controls in force are known (not before the first sample).
        if (cal->controls().empty() || cal->controls().ToNs(cal->controls().TimeAt(0)) > t) return;
        cal->Initialize(t, ps.xytheta, ps.covariance, prior, prior_cov);
      } else if (ps.utime <= last_pose_utime || t <= cal->time_ns()) {
        frames_out_of_order.fetch_add(1);  // repeated or earlier than the last: not used
        return;
      } else if (ps.utime - last_pose_utime > max_gap_us) {
        cal->ResetPose(t, ps.xytheta, ps.covariance);
        run_resets.fetch_add(1);
        consecutive_gated = 0;
      } else {
        const UpdateResult r = cal->AddPose(t, ps.xytheta, ps.covariance, cfg.filter.gate_nis);
        if (r.gated) {
          poses_gated.fetch_add(1);
          if (++consecutive_gated >= cfg.filter.divergence_gated) recover(ps);
        } else if (r.ok) {
          consecutive_gated = 0;
          updates.fetch_add(1);
          check->Add(t, r, cal->state(), cal->controls());
        }
      }
      last_pose_utime = ps.utime;
      if (recent.full()) recent.pop();
      recent.push(ps);
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
      const bool no_more_controls = controls_done.load() && control_q.size() == 0 && !held_jump;
      if (no_more_controls) drain_controls();
      // The controls jumped back and the poses did not follow: the controls alone start
      // the new time base (live after a second; lossless when the poses have ended).
      if (held_jump && pending.empty() &&
          (poses_over || (!lossless && MonotonicNs() - held_since_mono > kNsPerSecond))) {
        take_jump("the control clock", held_jump->utime, true);
      }
      // A pose is processed once the controls up to its time are in, or the controls
      // stream has ended, or (live) it has waited max_control_delay_s.
      while (!pending.empty()) {
        const PoseSample& f = pending.front();
        // Controls jumped back: no more controls will come on the old time base.
        const bool controls_in = max_control_utime >= f.utime || held_jump.has_value();
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
    h.schema_version = 2;
    h.utime = Now();
    h.source = source->name();
    h.frame_rate_hz = static_cast<double>(now.frames_captured - prev->frames_captured) / period_s;
    h.frames_captured = now.frames_captured;
    h.frames_dropped_device = now.frames_dropped_device;
    h.frames_dropped_queue = now.frames_dropped_queue;
    h.poses_published = poses_published.load();
    h.controls_received = now.controls_received;
    h.messages_rejected = now.controls_rejected;
    h.frames_bad = now.frame_errors;
    h.frames_out_of_order = now.frames_out_of_order;
    h.controls_out_of_order = now.controls_out_of_order;
    h.controls_late = now.controls_late;
    h.poses_gated = now.poses_gated;
    h.filter_resets = now.filter_resets;
    h.time_resets = now.time_resets;
    h.discarded_at_reset = now.discarded_at_reset;
    h.source_restarts = now.source_restarts;
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
    if (now.filter_resets > prev->filter_resets) add("filter diverged and was restarted from a batch fit");
    if (now.time_resets > prev->time_resets) add("a clock jumped back: new time base");
    if (now.frames_out_of_order > prev->frames_out_of_order) add("frames with repeated or earlier timestamps");
    if (now.controls_rejected > prev->controls_rejected) {
      std::lock_guard lock(status_mu);
      add("rejected control messages (last: " + last_reject + ")");
    }
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
    d.frames_out_of_order = frames_out_of_order.load();
    d.controls_late = controls_late.load();
    d.filter_resets = filter_resets.load();
    d.time_resets = time_resets.load();
    d.discarded_at_reset = discarded_at_reset.load();
    d.source_restarts = source_restarts.load();
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
          // Receive stamp on the pipeline's time base (monotonic, mapped once): an NTP step of
          // the realtime clock does not make controls jump against frames.
          self->OnControls(rbuf->data, rbuf->data_size, MonotonicToUtime(MonotonicNs()));
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
      "kincald: {} frames ({} dropped by the device, {} by the queue, {} bad, {} out of order), {} valid poses, "
      "{} updates, {} gated, {} runs, {} filter resets, {} time resets, {} source restarts; {} controls ({} rejected, "
      "{} out of order, {} late); log {} written / {} lost; latency p50 {:.3f} ms p99 {:.3f} ms",
      c.frames_captured, c.frames_dropped_device, c.frames_dropped_queue, c.frame_errors, c.frames_out_of_order,
      c.poses_valid, c.updates, c.poses_gated, c.run_resets + (c.updates > 0 ? 1 : 0), c.filter_resets, c.time_resets,
      c.source_restarts, c.controls_received, c.controls_rejected, c.controls_out_of_order, c.controls_late,
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
