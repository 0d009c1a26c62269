// The simulated camera: a scenario's robot rendered through the synthetic camera.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <kincal/controls_t.hpp>
#include <kincal/truth_t.hpp>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <random>
#include <thread>

#include "daemon/drive_link.h"
#include "daemon/sources.h"
#include "kincal/angles.h"
#include "kincal/sim/scenario.h"
#include "kincal/sim/simulator.h"
#include "kincal/vision/target.h"

namespace kincal::daemon {
namespace {

// A scenario that does not fit the config; thrown by the constructor below and caught in
// MakeSimSource, never outside this file.
class ScenarioMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A value, or its error as the ScenarioMismatch the constructor below reports with.
template <typename T>
T OrThrow(StatusOr<T> v) {
  if (!v.ok()) throw ScenarioMismatch(v.status().message());
  return std::move(v).value();
}

class SimSource final : public FrameSource {
 public:
  SimSource(const SimSourceOptions& c, const VisionSetup& v, ControlIntake controls,
            NetworkPublish publish, DriveLink* drive)
      : cfg_(c),
        vis_(v),
        sc_(OrThrow(LoadScenario(c.sim.scenario))),
        truth_(OrThrow(MakeSystem(sc_.model, sc_.hidden_effects))),
        intake_(std::move(controls)),
        publish_(std::move(publish)),
        drive_(drive),
        rng_(c.sim.seed != 0 ? c.sim.seed : sc_.seed),
        fault_rng_((c.sim.seed != 0 ? c.sim.seed : sc_.seed) ^ 0x9e3779b97f4a7c15ULL) {
    if (sc_.model != c.robot_model) {
      throw ScenarioMismatch(c.sim.scenario + ": scenario model '" + sc_.model +
                             "' differs from robot.model '" + c.robot_model + "' in " +
                             (c.config_file.empty() ? "the config" : c.config_file));
    }
    const int nc = truth_.num_controls();
    if (static_cast<int>(sc_.control_low.size()) != nc ||
        static_cast<int>(sc_.control_high.size()) != nc) {
      throw ScenarioMismatch(c.sim.scenario + ": controls.low/high need " + std::to_string(nc) +
                             " values");
    }
    p_true_ = OrThrow(ParamsFrom(truth_, sc_.truth, c.sim.scenario + ": truth"));
    if (sc_.profile != "smooth" && sc_.profile != "piecewise")
      throw ScenarioMismatch(c.sim.scenario + ": controls.profile must be smooth or piecewise");
    end_ = SecondsToNs(c.sim.duration_s > 0 ? c.sim.duration_s : sc_.duration_s);
    cmd_ = ControlSignal(nc, 0);
    NextChunk();
    x_ = truth_.MakeState(0.0, 0.0, Heading(), p_true_, cmd_, 0.0);
    render_.noise_sigma = c.sim.noise_grey;
    render_.background = vis_.layout.dark_on_light ? 200.0 : 40.0;
    render_.foreground = vis_.layout.dark_on_light ? 40.0 : 200.0;
    msg_.schema_version = 1;
    msg_.model = sc_.model;
    msg_.num_controls = nc;
    for (const auto& ch : truth_.model().controls()) msg_.names.push_back(ch.name);
    msg_.values.assign(static_cast<size_t>(nc), 0.0);
    InitTruthMessage();
  }

  std::string name() const override { return "sim(" + cfg_.sim.scenario + ")"; }
  Status Start() override {
    start_utime_ = PipelineUtime(MonotonicNs());
    start_mono_ = MonotonicNs();
    if (drive_ && first_rest_ >= 0) drive_->Expect(start_utime_ + first_rest_ / 1000);
    return {};
  }
  void Stop() override {
    stopped_ = true;
    if (drive_) drive_->Cancel();
  }
  SourceCapabilities capabilities() const override {
    return {.lossless = cfg_.sim.speed <= 0,
            .carries_controls = !cfg_.sim.controls_via_lcm,
            .controls_end_with_frames = true,
            .can_reopen = false};
  }

  SourceStatus Next(Frame* f, int /*timeout_ms*/, std::string* /*error*/) override {
    while (!stopped_ && k_ >= times_.size() && chunk_end_ < end_) NextChunk();
    if (stopped_ || k_ >= times_.size()) return SourceStatus::kEnd;
    const TimeNs t = times_[k_];
    // The robot's commands up to this frame, as it would publish them. A chunk's closing
    // sample is the next chunk's first: it is sent once that chunk exists.
    while (ci_ < cmd_.size()) {
      const TimeNs tc = cmd_.ToNs(cmd_.TimeAt(static_cast<int>(ci_)));
      if (tc > t || (tc >= chunk_end_ && chunk_end_ < end_)) break;
      EmitControl(ci_++);
    }
    if (cfg_.sim.speed > 0) {  // pace to simulated time / speed
      const TimeNs due = start_mono_ + static_cast<TimeNs>(static_cast<double>(t) / cfg_.sim.speed);
      while (!stopped_ && MonotonicNs() < due) {
        std::this_thread::sleep_for(
            std::chrono::nanoseconds(std::min<TimeNs>(due - MonotonicNs(), 50'000'000)));
      }
    }
    const double ts = cmd_.ToSeconds(t);
    truth_.Propagate(x_.data(), x_.data(), t_prev_, ts, cmd_, static_cast<const double*>(nullptr));
    t_prev_ = ts;
    bool in_view = false;
    if (carrying_ && t >= carry_until_) {  // put down at the centre, new heading
      x_[0] = 0.0;
      x_[1] = 0.0;
      x_[2] = Heading();
      carrying_ = false;
    }
    vision::Pose3 pose;
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    if (!carrying_) {
      truth_.Measure(x_.data(), target.data());
      pose = vision::CameraPoseOnFloor(vis_.floor, target, vis_.target_height_m);
      in_view = InView(pose);
      if (!in_view) {
        carrying_ = true;
        carry_until_ = t + SecondsToNs(cfg_.sim.carry_s);
      }
    }
    cv::Mat image;
    if (in_view) {
      auto rendered = vision::RenderTarget(vis_.camera, pose, vis_.layout, render_, rng_);
      image = rendered.image;
      AddFaults(pose, rendered.centres, &image);
    } else {
      image.create(vis_.camera.height, vis_.camera.width, CV_8UC1);
      cv::randn(image, render_.background, render_.noise_sigma);
    }
    FromGrey(image, f);
    f->utime = start_utime_ + t / 1000;
    f->device_utime = f->utime;
    f->sequence = sequence_++;
    f->arrival_mono_ns = MonotonicNs();
    PublishTruth(*f, carrying_ ? nullptr : &target);
    ++k_;
    return SourceStatus::kFrame;
  }

 private:
  // The run is simulated in chunks (sim.chunk_s): memory is bounded by the chunk's length
  // and the scenario's rates, not by the run's duration. A run no longer than one chunk
  // draws exactly what a whole-run simulation would.
  void NextChunk() {
    const size_t before = cmd_.size();
    cmd_.DiscardBefore(t_prev_);  // keeps the sample in force now
    ci_ -= std::min(ci_, before - cmd_.size());
    if (drive_) {
      NextLeg();
      return;
    }
    const TimeNs chunk = SecondsToNs(cfg_.sim.chunk_s);
    const TimeNs c0 = chunk_end_;
    const TimeNs c1 = end_ - c0 > chunk ? c0 + chunk : end_;
    if (sc_.profile == "smooth") {
      AppendSmoothRandom(&cmd_, c0, c1, sc_.control_low, sc_.control_high, sc_.min_period_s,
                         sc_.control_rate_hz, rng_);
    } else {
      AppendPiecewiseRandom(&cmd_, c0, c1, sc_.control_low, sc_.control_high, sc_.min_period_s,
                            3.0 * sc_.min_period_s, rng_);
    }
    times_ = FrameTimes(next_frame_, c1, sc_.camera, rng_, &next_frame_);
    k_ = 0;
    chunk_end_ = c1;
  }

  // guidance.drive: the next leg planned from the running estimate, where the robot stands
  // (its true pose: a real robot's driver would take the measured one from KINCAL_POSE),
  // then drive_pause_s at rest (the first chunk is that rest only: there is no estimate
  // yet). A leg that cannot be planned is a carry back to the centre.
  void NextLeg() {
    const TimeNs t0 = chunk_end_;
    TimeNs rest = t0;
    if (t0 > 0) {
      ControlSignal leg;
      const Status s = drive_->NextLeg(Eigen::Vector3d(x_[0], x_[1], x_[2]), sc_.control_rate_hz,
                                       kDriveWait, &leg);
      if (s.ok()) {
        for (int i = 0; i < static_cast<int>(leg.size()); ++i) {
          cmd_.Append(t0 + SecondsToNs(leg.TimeAt(i)),
                      std::span<const double>(leg.ValuesAt(i).data(), NumControls()));
        }
        rest = t0 + SecondsToNs(leg.TimeAt(static_cast<int>(leg.size()) - 1)) + ControlPeriod();
      } else {
        if (!stopped_ && drive_->legs_failed() == 1) {
          spdlog::warn("{}; the robot is carried back (further failures are counted)", s.message());
        }
        carrying_ = true;
        carry_until_ = t0 + SecondsToNs(cfg_.sim.carry_s);
        rest = carry_until_;
      }
    }
    const TimeNs c1 = std::min(end_, rest + SecondsToNs(cfg_.drive_pause_s));
    const ControlSignal::Values zero{};
    for (TimeNs t = rest; t < c1; t += ControlPeriod()) {
      cmd_.Append(t, std::span<const double>(zero.data(), NumControls()));
    }
    if (c1 < end_) ExpectRestAt(rest);
    times_ = FrameTimes(next_frame_, c1, sc_.camera, rng_, &next_frame_);
    k_ = 0;
    chunk_end_ = c1;
  }

  // The leg after this rest is planned from the first estimate at or after it (pipeline
  // time: the first rest is named once Start() has fixed the run's start).
  void ExpectRestAt(TimeNs rest) {
    if (start_utime_ != 0) {
      drive_->Expect(start_utime_ + rest / 1000);
    } else {
      first_rest_ = rest;
    }
  }

  size_t NumControls() const { return static_cast<size_t>(truth_.num_controls()); }

  TimeNs ControlPeriod() const { return SecondsToNs(1.0 / sc_.control_rate_hz); }

  double Heading() {
    return std::uniform_real_distribution<double>(-std::numbers::pi, std::numbers::pi)(rng_);
  }

  // Measurement faults: a reflection that looks like a marker somewhere near the target,
  // or a marker hidden behind something (the wrong number of markers).
  void AddFaults(const vision::Pose3& pose, const std::vector<Eigen::Vector2d>& centres,
                 cv::Mat* image) {
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const double r_px = vis_.camera.fx * vis_.layout.marker_radius_m / pose.t.z();
    if (cfg_.sim.reflection_prob > 0 && u01(fault_rng_) < cfg_.sim.reflection_prob) {
      // Within about one plate size of the target: inside the tracker's search region.
      const double reach = 2.0 * vis_.camera.fx * vis_.layout.plate_size_m.maxCoeff() / pose.t.z();
      const double dv = u01(fault_rng_) - 0.5;  // drawn in sequence: argument order is unspecified
      const double du = u01(fault_rng_) - 0.5;
      const Eigen::Vector2d c = centres.front() + Eigen::Vector2d(du, dv) * reach;
      cv::circle(*image, cv::Point(static_cast<int>(c.x() * 16), static_cast<int>(c.y() * 16)),
                 static_cast<int>(r_px * 16), cv::Scalar(render_.foreground), cv::FILLED,
                 cv::LINE_AA, 4);
    }
    if (cfg_.sim.occlusion_prob > 0 && u01(fault_rng_) < cfg_.sim.occlusion_prob) {
      const auto& c =
          centres[static_cast<size_t>(u01(fault_rng_) * static_cast<double>(centres.size())) %
                  centres.size()];
      cv::circle(*image, cv::Point(static_cast<int>(c.x()), static_cast<int>(c.y())),
                 static_cast<int>(2 * r_px + 2), cv::Scalar(render_.background), cv::FILLED);
    }
  }

  bool InView(const vision::Pose3& pose) const {
    const double m = cfg_.sim.margin_px;
    for (const auto& q : vis_.layout.markers) {
      const Eigen::Vector3d pc = pose.R * Eigen::Vector3d(q.x(), q.y(), 0.0) + pose.t;
      if (pc.z() <= 0) return false;
      const Eigen::Vector2d px = vis_.camera.Project(pc);
      if (px.x() < m || px.y() < m || px.x() > vis_.camera.width - 1 - m ||
          px.y() > vis_.camera.height - 1 - m)
        return false;
    }
    return true;
  }

  // The parts of the truth message that never change: the parameters' names and values.
  void InitTruthMessage() {
    truth_msg_.schema_version = 1;
    truth_msg_.model = sc_.model;
    truth_msg_.scenario = cfg_.sim.scenario;
    truth_msg_.num_params = truth_.num_params();
    for (int i = 0; i < truth_.num_params(); ++i) {
      truth_msg_.names.push_back(truth_.params()[static_cast<size_t>(i)].name);
      truth_msg_.values.push_back(p_true_[i]);
    }
  }

  // The truth at this frame: where the tracked point stands (none while carried).
  void PublishTruth(const Frame& f, const Eigen::Vector3d* target) {
    truth_msg_.utime = f.utime;
    truth_msg_.frame_sequence = f.sequence;
    truth_msg_.on_floor = target != nullptr;
    truth_msg_.x = target ? target->x() : 0.0;
    truth_msg_.y = target ? target->y() : 0.0;
    truth_msg_.theta = target ? target->z() : 0.0;
    const int n = truth_msg_.getEncodedSize();
    truth_buf_.resize(static_cast<size_t>(n));  // the same size every frame: no allocation
    truth_msg_.encode(truth_buf_.data(), 0, n);
    publish_(cfg_.truth_channel, truth_buf_.data(), truth_buf_.size(), f.utime);
  }

  void EmitControl(size_t i) {
    const auto& v = cmd_.ValuesAt(static_cast<int>(i));
    for (int k = 0; k < msg_.num_controls; ++k)
      msg_.values[static_cast<size_t>(k)] = v[static_cast<size_t>(k)];
    msg_.utime = start_utime_ + cmd_.ToNs(cmd_.TimeAt(static_cast<int>(i))) / 1000;
    msg_.sender_utime = msg_.utime;
    const int n = msg_.getEncodedSize();
    buf_.resize(static_cast<size_t>(n));
    msg_.encode(buf_.data(), 0, n);
    publish_(cfg_.controls_channel, buf_.data(), buf_.size(), kNetworkOnly);
    if (!cfg_.sim.controls_via_lcm) intake_(buf_.data(), buf_.size(), msg_.utime);
  }

  const SimSourceOptions cfg_;
  const VisionSetup vis_;  // a copy: the source owns what it renders with
  Scenario sc_;
  System truth_;
  ControlIntake intake_;
  NetworkPublish publish_;
  DriveLink* const drive_;  // guidance.drive, else null
  std::mt19937_64 rng_;
  std::mt19937_64 fault_rng_;  // its own stream: faults do not change the rest of the simulation
  VecN<kMaxState> p_true_;
  ControlSignal cmd_;
  std::vector<TimeNs> times_;  // frame times of the current chunk
  TimeNs end_ = 0;             // the run's end
  TimeNs chunk_end_ = 0;
  TimeNs next_frame_ = 0;
  StateVec x_;
  vision::RenderOptions render_;
  kincal::controls_t msg_;
  std::vector<uint8_t> buf_;
  kincal::truth_t truth_msg_;
  std::vector<uint8_t> truth_buf_;
  size_t k_ = 0, ci_ = 0;
  int64_t sequence_ = 0;
  double t_prev_ = 0.0;
  bool carrying_ = false;
  TimeNs carry_until_ = 0;
  int64_t start_utime_ = 0;
  TimeNs start_mono_ = 0;
  TimeNs first_rest_ = -1;  // guidance.drive: the first rest, until Start()
  std::atomic<bool> stopped_{false};
};

}  // namespace

StatusOr<std::unique_ptr<FrameSource>> MakeSimSource(const SimSourceOptions& c,
                                                     const VisionSetup& v, ControlIntake controls,
                                                     NetworkPublish publish, DriveLink* drive) {
  try {
    return std::unique_ptr<FrameSource>(
        std::make_unique<SimSource>(c, v, std::move(controls), std::move(publish), drive));
  } catch (const ScenarioMismatch& e) {
    return Status::Error(e.what());
  }
}

}  // namespace kincal::daemon
