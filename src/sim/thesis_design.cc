#include "sim/thesis_design.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kincal/angles.h"

namespace kincal {
namespace {

// Placement tries per run, and the margin the plate keeps from the frame's edge (px).
constexpr int kPlacementTries = 4000;
constexpr double kPlacementMarginPx = 6.0;
// A pose error this far beyond its covariance is a gross error (a wrong marker), counted
// apart from the pose statistics.
constexpr double kGrossNees = 100.0;

std::vector<std::array<double, 2>> DrawGains(const WheelRateErrors& w, std::mt19937_64& rng) {
  std::vector<std::array<double, 2>> gains;
  if (w.gain_sigma > 0.0) {
    std::normal_distribution<double> g(0.0, w.gain_sigma);
    const int bands = 1 + static_cast<int>(60.0 / w.band_width_rad_s);
    for (int b = 0; b < bands; ++b) {
      const double left = g(rng);
      gains.push_back({left, g(rng)});
    }
  }
  return gains;
}

// Stamps on a timer of the recording's clock (floor to its tick): the tick's phase is
// the clock's, not the run's, so every frame's stamp error is uniform within a tick.
void StampOnTick(const ThesisOptions& o, std::vector<PoseMeasurement>* meas) {
  if (o.stamp_step_s <= 0.0) return;
  const TimeNs step = SecondsToNs(o.stamp_step_s);
  for (auto& m : *meas) m.t_ns = m.t_ns / step * step;
}

std::array<double, 2> Realised(const ThesisOptions& o, const ThesisDesign& d, int k) {
  return {RealisedWheelRate(kThesisControls[k][0], 0, o.wheel, d.gains),
          RealisedWheelRate(kThesisControls[k][1], 1, o.wheel, d.gains)};
}

// The true target poses of a run driven by the realised controls from its start pose.
std::vector<TrajectoryPoint> RunTruth(const System& truth, const Eigen::Vector3d& params,
                                      const ThesisDesign& d, const ThesisRun& run,
                                      std::span<const TimeNs> times) {
  const VecN<kMaxState> p = params;
  const Eigen::Vector3d& s = run.start_pose;
  const StateVec x0 =
      truth.MakeState(s.x(), s.y(), s.z(), p, d.realised, d.realised.ToSeconds(run.t0));
  return SimulateTruth(truth, x0, d.realised, times);
}

// The first round's world: runs of a full turn, Gaussian pose noise, random start poses
// (the random stream in the order earlier results were drawn with).
ThesisDesign IdealDesign(const System& truth, const Eigen::Vector3d& params, const ThesisOptions& o,
                         const Eigen::Matrix3d& R, std::mt19937_64& rng) {
  ThesisDesign d;
  std::uniform_real_distribution<double> pos(-0.2, 0.2), ang(-std::numbers::pi, std::numbers::pi);
  d.gains = DrawGains(o.wheel, rng);
  TimeNs t = 0;
  for (int k = 0; k < o.runs; ++k) {
    const double wl = kThesisControls[k][0], wr = kThesisControls[k][1];
    const double omega = (params[1] * wr - params[0] * wl) / params[2];
    const double one_turn = 2.0 * std::numbers::pi / std::max(std::abs(omega), 1e-6);
    const double duration = std::max(one_turn, o.min_frames / o.timing.rate_hz);
    ThesisRun run;
    run.index = k;
    run.t0 = t;
    run.t1 = t + SecondsToNs(duration);
    const std::array<double, 2> u = {wl, wr};
    AppendConstant(&d.controls, run.t0, run.t1, u);
    AppendConstant(&d.realised, run.t0, run.t1, Realised(o, d, k));
    d.runs.push_back(run);
    t = run.t1 + kNsPerSecond;  // 1 s pause between experiments
  }
  for (ThesisRun& run : d.runs) {
    const auto times = FrameTimes(run.t0, run.t1, o.timing, rng);
    // In a fixed sequence (argument order is unspecified): heading, y, x, as GCC evaluated it.
    const double sth = ang(rng), sy = pos(rng), sx = pos(rng);
    run.start_pose = Eigen::Vector3d(sx, sy, sth);
    run.meas = MeasurePoses(RunTruth(truth, params, d, run, times), R, run.index, rng);
    StampOnTick(o, &run.meas);
    d.all.insert(d.all.end(), run.meas.begin(), run.meas.end());
    d.starts.push_back(run.start_pose);
  }
  return d;
}

// Exactly `frames` frame times from t0, with the options' stalls and drops.
std::vector<TimeNs> RunFrameTimes(TimeNs t0, int frames, const FrameTimingOptions& timing,
                                  std::mt19937_64& rng) {
  std::vector<TimeNs> times;
  TimeNs next = t0;
  while (static_cast<int>(times.size()) < frames) {
    const TimeNs span = SecondsToNs(frames / timing.rate_hz);
    const auto more = FrameTimes(next, next + span, timing, rng, &next);
    times.insert(times.end(), more.begin(), more.end());
  }
  times.resize(static_cast<size_t>(frames));
  return times;
}

// As the thesis's experimenter did (§6.2.3): a start pose whose expected (nominal) path
// keeps the whole plate in view; the best of the tries when none does.
Eigen::Vector3d PlaceInView(const System& sys, const ThesisDesign& d, const ThesisRun& run,
                            std::span<const TimeNs> times, const ThesisVision& vision,
                            std::mt19937_64& rng) {
  std::uniform_real_distribution<double> pos(-0.6, 0.6), ang(-std::numbers::pi, std::numbers::pi);
  const VecN<kMaxState> nominal = Eigen::Vector3d(kThesisRL, kThesisRR, kThesisD);
  Eigen::Vector3d best = Eigen::Vector3d::Zero();
  size_t best_in = 0;
  for (int attempt = 0; attempt < kPlacementTries; ++attempt) {
    const double th = ang(rng), y = pos(rng), x = pos(rng);
    const Eigen::Vector3d start(x, y, th);
    if (!PlateInView(vision, start, kPlacementMarginPx)) continue;
    const StateVec x0 = sys.MakeState(x, y, th, nominal, d.controls, d.controls.ToSeconds(run.t0));
    const auto path = SimulateTruth(sys, x0, d.controls, times);
    size_t in = 0;
    for (const auto& p : path) in += PlateInView(vision, p.target, kPlacementMarginPx) ? 1 : 0;
    if (in > best_in) {
      best_in = in;
      best = start;
    }
    if (in == path.size()) break;
  }
  return best;
}

// Pose variance a timer tick adds, propagated through the nominal motion: a stamp uniform
// within one tick of the true time displaces the pose by the velocity times that error.
Eigen::Matrix3d TickCovariance(const ThesisOptions& o, double wl, double wr, double heading) {
  const double v = 0.5 * (kThesisRL * wl + kThesisRR * wr);
  const double w = (kThesisRR * wr - kThesisRL * wl) / kThesisD;
  const Eigen::Vector3d g(v * std::cos(heading), v * std::sin(heading), w);
  return (o.stamp_step_s * o.stamp_step_s / 12.0) * g * g.transpose();
}

void MeasureRun(const System& truth, const Eigen::Vector3d& params, const ThesisOptions& o,
                PixelPoseMeter* meter, std::span<const TimeNs> times, ThesisDesign* d,
                ThesisRun* run, std::mt19937_64& rng) {
  const auto traj = RunTruth(truth, params, *d, *run, times);
  PoseErrorStats& st = d->pose_errors;
  for (const auto& tp : traj) {
    PoseMeasurement m;
    m.t_ns = tp.t_ns;
    m.segment = run->index;
    ++st.frames;
    if (!meter->Measure(tp.target, rng, &m.z, &m.R)) {
      ++st.lost;
      continue;
    }
    Eigen::Vector3d e = m.z - tp.target;
    e.z() = WrapAngle(e.z());
    const double nees = e.dot(m.R.ldlt().solve(e));
    if (nees > kGrossNees) {
      ++st.gross;  // kept in the data (the estimators must cope), not in the statistics
    } else {
      st.sum_sq += e.cwiseAbs2();
      st.sum_nees += nees;
    }
    run->meas.push_back(m);
  }
  StampOnTick(o, &run->meas);
  if (o.stamp_step_s > 0.0) {
    // The estimators know the tick: the true time lies within [stamp, stamp + tick), so
    // they take its middle and the uniform spread's variance.
    const TimeNs half = SecondsToNs(0.5 * o.stamp_step_s);
    for (auto& m : run->meas) {
      m.t_ns += half;
      m.R += TickCovariance(o, kThesisControls[run->index][0], kThesisControls[run->index][1],
                            m.z.z());
    }
  }
}

ThesisDesign RealisticDesign(const System& truth, const Eigen::Vector3d& params,
                             const ThesisOptions& o, const Eigen::Matrix3d& R,
                             PixelPoseMeter* meter, std::mt19937_64& rng) {
  ThesisDesign d;
  d.gains = DrawGains(o.wheel, rng);
  TimeNs t = 0;
  for (int k = 0; k < o.runs; ++k) {
    ThesisRun run;
    run.index = k;
    run.t0 = t;
    const auto times = RunFrameTimes(run.t0, o.frames_per_run, o.timing, rng);
    run.t1 = times.back() + SecondsToNs(1.0 / o.timing.rate_hz);  // stops a frame later
    const std::array<double, 2> u = {kThesisControls[k][0], kThesisControls[k][1]};
    AppendConstant(&d.controls, run.t0, run.t1, u);
    AppendConstant(&d.realised, run.t0, run.t1, Realised(o, d, k));
    if (meter != nullptr) {
      run.start_pose = PlaceInView(truth, d, run, times, meter->vision(), rng);
      MeasureRun(truth, params, o, meter, times, &d, &run, rng);
    } else {
      std::uniform_real_distribution<double> pos(-0.2, 0.2),
          ang(-std::numbers::pi, std::numbers::pi);
      // In a fixed sequence (argument order is unspecified): heading, y, x, as GCC evaluated
      // the constructor's arguments before.
      const double sth = ang(rng), sy = pos(rng), sx = pos(rng);
      run.start_pose = Eigen::Vector3d(sx, sy, sth);
      run.meas = MeasurePoses(RunTruth(truth, params, d, run, times), R, k, rng);
      StampOnTick(o, &run.meas);
    }
    d.all.insert(d.all.end(), run.meas.begin(), run.meas.end());
    d.starts.push_back(run.start_pose);
    d.runs.push_back(std::move(run));
    t = d.runs.back().t1 + kNsPerSecond;
  }
  return d;
}

}  // namespace

ThesisDesign MakeThesisDesign(const System& truth, const Eigen::Vector3d& params,
                              const ThesisOptions& o, const Eigen::Matrix3d& R,
                              PixelPoseMeter* meter, std::mt19937_64& rng) {
  if (o.frames_per_run == 0 && meter == nullptr) return IdealDesign(truth, params, o, R, rng);
  return RealisticDesign(truth, params, o, R, meter, rng);
}

}  // namespace kincal
