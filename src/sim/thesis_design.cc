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

// What the estimators make of a pose stamped on a timer tick, through the nominal motion.
// The true time is the stamp's middle plus e, uniform within the tick (variance s2): the
// pose moved by p(t + e) - p(t) = e v T + e^2 / 2 v w N along the arc (T its direction
// at the measured heading, N its normal towards the turn's centre). To first order that
// is the velocity times e: a covariance along (v T, w). To second order, seen from the
// measured pose, the pose it is compared with lies e^2 / 2 v w outside the arc on
// average: left alone, that bias grows every circle by s2 w^2 / 2 of its radius (measured:
// 1e-4 of the lengths at a 10 ms tick, quadrupling with a 20 ms one). Moving the
// measurement by the mean of that term removes it; its spread about that mean (e^4's
// mean is h^4 / 80 for a tick h) joins the covariance.
void AccountForTick(const ThesisOptions& o, double wl, double wr, PoseMeasurement* m) {
  const double v = 0.5 * (kThesisRL * wl + kThesisRR * wr);
  const double w = (kThesisRR * wr - kThesisRL * wl) / kThesisD;
  const double h = o.stamp_step_s, s2 = h * h / 12.0, e4 = h * h * h * h / 80.0;
  const double c = std::cos(m->z.z()), s = std::sin(m->z.z());
  const Eigen::Vector3d g(v * c, v * s, w);
  const Eigen::Vector3d n(-s, c, 0.0);
  const double a = 0.5 * v * w;  // the second-order term is a e^2 n
  m->R += s2 * g * g.transpose() + a * a * (e4 - s2 * s2) * n * n.transpose();
  m->z += a * s2 * n;
}

// Stamps a run's poses on a timer of the recording's clock (floor to its tick; the tick's
// phase is the clock's, not the run's, so every stamp's error is uniform within a tick),
// and gives the estimators what they know of it: the true time lies within [stamp, stamp +
// tick), so they take its middle, the uniform spread's variance and its second-order mean.
void StampOnTick(const ThesisOptions& o, ThesisRun* run) {
  if (o.stamp_step_s <= 0.0) return;
  const TimeNs step = SecondsToNs(o.stamp_step_s), half = SecondsToNs(0.5 * o.stamp_step_s);
  for (auto& m : run->meas) {
    m.t_ns = m.t_ns / step * step + half;
    AccountForTick(o, kThesisControls[run->index][0], kThesisControls[run->index][1], &m);
  }
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
    StampOnTick(o, &run);
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
    // Judged against what a noise-free measurement gives with the day's calibration (its
    // floor is not the true one: the calibration error is not the solver's noise).
    const Eigen::Vector3d expected = o.pixel.calibration.enabled
                                         ? MapPose(meter->vision(), meter->calibrated(), tp.target)
                                         : tp.target;
    Eigen::Vector3d e = m.z - expected;
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
  StampOnTick(o, run);
}

StatusOr<ThesisDesign> RealisticDesign(const System& truth, const Eigen::Vector3d& params,
                                       const ThesisOptions& o, const Eigen::Matrix3d& R,
                                       PixelPoseMeter* meter, std::mt19937_64& rng) {
  ThesisDesign d;
  d.gains = DrawGains(o.wheel, rng);
  TimeNs t = 0;
  for (int k = 0; k < o.runs; ++k) {
    if (meter != nullptr && o.pixel.calibration.enabled &&
        k % o.pixel.calibration.runs_per_day == 0) {
      const Status day = meter->BeginDay();
      if (!day.ok())
        return Status::Error("experiment " + std::to_string(k + 1) + ": " + day.message());
      d.days.push_back({CompareFloorMaps(meter->vision(), meter->calibrated()),
                        meter->calibrated_scale_sigma(), 0});
    }
    if (!d.days.empty()) ++d.days.back().runs;
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
      StampOnTick(o, &run);
    }
    d.all.insert(d.all.end(), run.meas.begin(), run.meas.end());
    d.starts.push_back(run.start_pose);
    d.runs.push_back(std::move(run));
    t = d.runs.back().t1 + kNsPerSecond;
  }
  return d;
}

}  // namespace

StatusOr<ThesisDesign> MakeThesisDesign(const System& truth, const Eigen::Vector3d& params,
                                        const ThesisOptions& o, const Eigen::Matrix3d& R,
                                        PixelPoseMeter* meter, std::mt19937_64& rng) {
  if (o.frames_per_run == 0 && meter == nullptr) return IdealDesign(truth, params, o, R, rng);
  return RealisticDesign(truth, params, o, R, meter, rng);
}

}  // namespace kincal
