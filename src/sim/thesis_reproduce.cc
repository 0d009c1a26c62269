// One reproduction of the thesis experiment: for each trial, the design (kincal/sim/thesis.h),
// the joint and per-experiment calibrations of every estimator, and the bound.
#include <cmath>
#include <memory>

#include "kincal/check.h"
#include "kincal/estimation/online_calibrator.h"
#include "kincal/sim/thesis.h"
#include "sim/lookup_gain.h"
#include "sim/thesis_design.h"

namespace kincal {
namespace {

struct Estimate {
  Eigen::VectorXd params;
  Eigen::MatrixXd cov;
};

// Through pixels a pose is now and then far off (a marker taken for another in a noisy
// frame: about one in 20,000 frames here); the filters refuse a pose whose normalised
// innovation exceeds this (chi-square with 3 degrees of freedom: p = 1.4e-5), and the
// batch fits use a Huber loss of this scale on whitened residuals, as a user would.
constexpr double kPixelGateNis = 25.0;
constexpr double kPixelHuberScale = 3.0;

// Runs one filter over the given runs; the parameters carry across runs. `gate_nis` > 0
// refuses poses beyond it, counted in *gated.
Estimate RunFilter(const System& sys, const std::string& filter, const ThesisDesign& d,
                   std::span<const ThesisRun> runs, const Eigen::VectorXd& guess,
                   const Eigen::MatrixXd& prior_cov, double gate_nis = 0.0, int* gated = nullptr) {
  OnlineCalibratorOptions opt;
  opt.filter = filter;
  OnlineCalibrator cal(sys, opt, d.controls.origin_ns());
  cal.controls() = d.controls;
  bool first = true;
  for (const ThesisRun& run : runs) {
    if (run.meas.empty()) continue;
    const auto& m0 = run.meas.front();
    if (first) {
      const VecN<kMaxState> p = guess;
      const StateMat P = prior_cov;
      cal.Initialize(m0.t_ns, m0.z, m0.R, p, P);
      first = false;
    } else {
      cal.ResetPose(m0.t_ns, m0.z, m0.R);
    }
    for (size_t i = 1; i < run.meas.size(); ++i) {
      const auto r = cal.AddPose(run.meas[i].t_ns, run.meas[i].z, run.meas[i].R, gate_nis);
      if (r.gated && gated != nullptr) ++*gated;
    }
  }
  const int n = sys.num_params();
  return {cal.params().head(n), cal.params_covariance().topLeftCorner(n, n)};
}

// Batch fit by continuation: open-loop over a long run, a guess a few percent off lies
// outside the optimum's basin (seen: 1 trial in 32 stopped at 46 % NNDE). Fit the first
// quarter of every run first, then every measurement from there.
Estimate RunBatch(const System& sys, const ThesisDesign& d, const Eigen::VectorXd& guess,
                  const BatchOptions& bopt) {
  std::vector<PoseMeasurement> early;
  for (const ThesisRun& run : d.runs) {
    for (const auto& m : run.meas) {
      if (m.t_ns <= run.t0 + (run.t1 - run.t0) / 4) early.push_back(m);
    }
  }
  BatchOptions quick = bopt;
  quick.compute_covariance = false;
  const BatchResult b0 = FitBatch(sys, d.controls, early, guess, quick);
  KINCAL_CHECK(b0.status.ok(), b0.status.message().c_str());  // simulated: a bug if not
  const BatchResult b = FitBatch(sys, d.controls, d.all, b0.params, bopt);
  KINCAL_CHECK(b.status.ok(), b.status.message().c_str());
  const int n = sys.num_params();
  return {b.params, b.covariance_ok ? b.covariance : Eigen::MatrixXd::Constant(n, n, std::nan(""))};
}

// The joint estimates' error statistics, accumulated over trials.
class JointTally {
 public:
  explicit JointTally(const Eigen::Vector3d& truth) : truth_(truth) {}
  void SetTruth(const Eigen::Vector3d& truth) { truth_ = truth; }
  // The variance of the lengths' common scale the poses carry (the camera's calibration:
  // a pose scale s makes every length (1 + s) times its own), added to every estimate's
  // covariance as s^2 a a' (a consider covariance: not estimated, but not ignored).
  void SetScaleVariance(double v) { scale_variance_ = v; }
  void Record(const std::string& name, const Estimate& e, ThesisResult* res) {
    const Eigen::Vector3d est = e.params.head(3);
    const Eigen::Matrix3d cov = e.cov.topLeftCorner(3, 3) + scale_variance_ * est * est.transpose();
    const double nnde = Nnde(est, truth_);
    sq_[name] += nnde * nnde;
    res->joint_trial_nnde[name].push_back(nnde);
    res->joint_estimate[name] = est;
    res->joint_sigma[name] = cov.diagonal().cwiseSqrt();
    const Eigen::Vector3d err = est - truth_;
    int& inside = inside_[name];
    for (int i = 0; i < 3; ++i) inside += std::abs(err[i]) <= 3.0 * std::sqrt(cov(i, i)) ? 1 : 0;
    nees_[name] += err.dot(cov.ldlt().solve(err));
  }
  void Finish(int trials, ThesisResult* res) const {
    for (const auto& [name, sq] : sq_) {
      res->joint_nnde_percent[name] = 100.0 * std::sqrt(sq / trials);
      res->joint_within_3sigma[name] = inside_.at(name) / (3.0 * trials);
      res->joint_nees[name] = nees_.at(name) / trials;
    }
  }

 private:
  Eigen::Vector3d truth_;
  double scale_variance_ = 0.0;
  std::map<std::string, double> sq_, nees_;
  std::map<std::string, int> inside_;
};

// The per-experiment statistics, accumulated over trials (RMS NNDE as the bound; the
// Table 6-5 statistics averaged).
struct PerRunTally {
  std::map<std::string, double> sum_sq;
  std::map<std::string, TableStats> stats;
  double bound_sum_sq = 0.0;
  int bound_count = 0;
};

void PerRunCalibrations(const System& sys, const std::string& f, const ThesisDesign& d,
                        const Eigen::Vector3d& truth, const Eigen::VectorXd& guess,
                        const Eigen::MatrixXd& prior_cov, double gate, PerRunTally* tally,
                        ThesisResult* res) {
  std::vector<Eigen::Vector3d> est, sigma;
  for (const ThesisRun& run : d.runs) {
    const Estimate e =
        RunFilter(sys, f, d, std::span<const ThesisRun>(&run, 1), guess, prior_cov, gate);
    est.push_back(e.params.head(3));
    sigma.push_back(e.cov.topLeftCorner(3, 3).diagonal().cwiseSqrt());
    tally->sum_sq[f] += std::pow(Nnde(est.back(), truth), 2);  // RMS, as the bound
  }
  const TableStats s = PerRunStats(est, truth);
  TableStats& acc = tally->stats[f];
  acc.mean_nnde += s.mean_nnde;
  acc.nnde_of_mean += s.nnde_of_mean;
  acc.speed_scatter += s.speed_scatter;
  acc.turn_scatter += s.turn_scatter;
  res->per_run_estimate[f] = std::move(est);
  res->per_run_sigma[f] = std::move(sigma);
}

// The bound is the information of the Gaussian measurements: no robust loss.
BatchOptions WithoutLoss(BatchOptions o) {
  o.huber_scale = 0.0;
  return o;
}

// The system with the look-up-table gains, and how many speed bands it has.
struct GainModel {
  std::unique_ptr<System> sys;
  int bands = 0;
};

GainModel MakeGainModel(const System& bare, const ThesisOptions& o) {
  double fastest = 0.0;
  for (int k = 0; k < o.runs; ++k) {
    fastest = std::max({fastest, kThesisControls[k][0], kThesisControls[k][1]});
  }
  GainModel g;
  g.bands = 1 + static_cast<int>(fastest / o.wheel.band_width_rad_s);
  g.sys = std::make_unique<System>(
      bare.model_ptr(), std::vector<std::shared_ptr<const Effect>>{
                            MakeLookupTableGain(bare.model(), g.bands, o.wheel.band_width_rad_s)});
  return g;
}

Eigen::VectorXd WithGains(const Eigen::Vector3d& model, const GainModel& g,
                          const std::vector<std::array<double, 2>>* gains) {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(3 + 2 * g.bands);
  p.head(3) = model;
  for (int b = 0; gains != nullptr && b < g.bands; ++b) {
    p[3 + b] = (*gains)[static_cast<size_t>(b)][0];
    p[3 + g.bands + b] = (*gains)[static_cast<size_t>(b)][1];
  }
  return p;
}

Eigen::MatrixXd WithGainsCov(const Eigen::Matrix3d& model_cov, const GainModel& g, double sigma) {
  Eigen::MatrixXd c = Eigen::MatrixXd::Identity(3 + 2 * g.bands, 3 + 2 * g.bands) * sigma * sigma;
  c.topLeftCorner(3, 3) = model_cov;
  return c;
}

// The joint fits with the look-up table's gains as nuisance parameters (each filter, and the
// batch); returns the expected NNDE of the model parameters' bound at the truth.
double FitWithGains(const GainModel& gm, const ThesisOptions& o, const ThesisDesign& d,
                    const Eigen::Vector3d& truth, const Eigen::Vector3d& guess,
                    const Eigen::Matrix3d& prior_cov, const BatchOptions& bopt, JointTally* joint,
                    ThesisResult* res) {
  const double gate = o.pixels ? kPixelGateNis : 0.0;
  const Eigen::VectorXd g0 = WithGains(guess, gm, nullptr);
  const Eigen::MatrixXd c0 = WithGainsCov(prior_cov, gm, o.wheel.gain_sigma);
  for (const auto& f : o.filters) {
    int gated = 0;
    joint->Record(f + "+gains", RunFilter(*gm.sys, f, d, d.runs, g0, c0, gate, &gated), res);
    if (gate > 0.0) res->poses_gated[f + "+gains"] += gated;
  }
  BatchOptions gopt = bopt;
  gopt.prior = ParamPrior{g0, c0};
  if (o.batch) joint->Record("batch+gains", RunBatch(*gm.sys, d, g0, gopt), res);
  const BatchResult gb = BoundAt(*gm.sys, d.controls, d.all, WithGains(truth, gm, &d.gains),
                                 d.starts, WithoutLoss(gopt));
  KINCAL_CHECK(gb.status.ok(), gb.status.message().c_str());
  return ExpectedNnde(gb.covariance.topLeftCorner(3, 3), truth);
}

// The Bayesian bound at the truth with the trials' prior: the joint one's expected NNDE
// (returned) and, with per_run, each run's alone (into *per_run).
double BoundTrial(const System& sys, const ThesisOptions& o, const ThesisDesign& d,
                  const Eigen::Vector3d& truth, const BatchOptions& bopt, PerRunTally* per_run) {
  const BatchResult bound = BoundAt(sys, d.controls, d.all, truth, d.starts, WithoutLoss(bopt));
  KINCAL_CHECK(bound.status.ok(), bound.status.message().c_str());
  if (o.per_run) {
    for (const ThesisRun& run : d.runs) {
      if (run.meas.empty()) continue;
      const BatchResult b1 =
          BoundAt(sys, d.controls, run.meas, truth, {run.start_pose}, WithoutLoss(bopt));
      KINCAL_CHECK(b1.status.ok(), b1.status.message().c_str());
      per_run->bound_sum_sq += std::pow(ExpectedNnde(b1.covariance, truth), 2);
      ++per_run->bound_count;
    }
  }
  return ExpectedNnde(bound.covariance, truth);
}

void FinishPerRun(const PerRunTally& per_run, const ThesisOptions& o, ThesisResult* res) {
  for (const auto& [name, sum] : per_run.sum_sq) {
    res->per_run_nnde_percent[name] = 100.0 * std::sqrt(sum / (o.runs * o.trials));
    TableStats s = per_run.stats.at(name);
    for (double* v : {&s.mean_nnde, &s.nnde_of_mean, &s.speed_scatter, &s.turn_scatter})
      *v /= o.trials;
    res->per_run_stats[name] = s;
  }
  if (per_run.bound_count > 0) {
    res->per_run_bound_nnde_percent = 100.0 * std::sqrt(per_run.bound_sum_sq / per_run.bound_count);
  }
}

void AddPoseErrors(const PoseErrorStats& trial, PoseErrorStats* sum) {
  sum->frames += trial.frames;
  sum->lost += trial.lost;
  sum->gross += trial.gross;
  sum->sum_sq += trial.sum_sq;
  sum->sum_nees += trial.sum_nees;
}

// The variance of the scale all runs' poses share: each day's calibration gives its
// floor's scale sigma; the joint estimate weighs each day by its share of the runs.
double PoseScaleVariance(const ThesisDesign& d) {
  double total = 0.0, v = 0.0;
  for (const auto& day : d.days) total += day.runs;
  for (const auto& day : d.days) v += std::pow(day.runs / total * day.scale_sigma, 2);
  return total > 0.0 ? v : 0.0;
}

// The idealised world's pose covariance: four markers at the corners of a 60 x 100 mm
// rectangle on the 80 x 120 mm plate, origin at their centroid, seen by the nadir camera.
Eigen::Matrix3d IdealPoseCovariance(const ThesisOptions& o) {
  const double focal_px = 0.5 * o.image_width_px / std::tan(0.5 * o.hfov_rad);
  const std::vector<Eigen::Vector2d> markers = {
      {0.05, 0.03}, {0.05, -0.03}, {-0.05, -0.03}, {-0.05, 0.03}};
  return PlanarPoseCovariance(o.camera_height_m, focal_px, markers, o.centroid_sigma_px);
}

// A trial's camera days: their scale variance into the joint tally (a consider
// covariance), their floor maps into the result.
void AddCameraDays(const ThesisDesign& d, JointTally* joint, ThesisResult* res) {
  joint->SetScaleVariance(PoseScaleVariance(d));
  for (const auto& day : d.days) {
    ++res->camera_days;
    res->camera_scale_rms += day.error.scale * day.error.scale;
    res->camera_bend_rms_m += day.error.rms_m * day.error.rms_m;
    res->camera_scale_sigma_rms += day.scale_sigma * day.scale_sigma;
  }
}

void FinishCameraDays(ThesisResult* res) {
  if (res->camera_days == 0) return;
  res->camera_scale_rms = std::sqrt(res->camera_scale_rms / res->camera_days);
  res->camera_bend_rms_m = std::sqrt(res->camera_bend_rms_m / res->camera_days);
  res->camera_scale_sigma_rms = std::sqrt(res->camera_scale_sigma_rms / res->camera_days);
}

void FinishPoses(const PoseErrorStats& poses, ThesisResult* res) {
  const int measured = poses.frames - poses.lost - poses.gross;
  res->frames_lost = poses.lost;
  res->frames_gross = poses.gross;
  if (measured > 0) {
    res->pose_rms_error = (poses.sum_sq / measured).cwiseSqrt();
    res->pose_nees = poses.sum_nees / measured;
  }
}

// The realistic world's meter (none without pixels), its image noise in `res`.
StatusOr<std::unique_ptr<PixelPoseMeter>> MakeMeter(const ThesisOptions& o, std::mt19937_64& rng,
                                                    ThesisResult* res) {
  if (!o.pixels) return std::unique_ptr<PixelPoseMeter>();
  PixelPoseOptions po = o.pixel;
  po.calibration.seed = o.seed ^ 0x5eed0ca11b4a7e5ULL;  // the days' stream, from the world's seed
  StatusOr<std::unique_ptr<PixelPoseMeter>> made =
      PixelPoseMeter::Make(ThesisTable63Vision(), po, rng);
  if (made.ok()) {
    res->image_noise_grey = made.value()->image_noise_grey();
    res->centroid_sigma_px = made.value()->measured_centroid_sigma_px();
  }
  return made;
}

}  // namespace

StatusOr<ThesisResult> ReproduceThesis(const ThesisOptions& o) {
  std::string error;
  if (!o.IsValid(&error)) return Status::Error("thesis: " + error);
  const System sys = MakeSystem("diffdrive").value();
  const Eigen::Vector3d nominal(kThesisRL, kThesisRR, kThesisD);
  const Eigen::Matrix3d R = IdealPoseCovariance(o);

  ThesisResult res;
  res.runs = o.runs;
  res.trials = o.trials;
  res.pose_cov = R;
  res.thesis_stats = ThesisTableStats();
  res.thesis_per_run_nnde_percent = 100.0 * res.thesis_stats.mean_nnde;

  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  StatusOr<std::unique_ptr<PixelPoseMeter>> made = MakeMeter(o, rng, &res);
  if (!made.ok()) return Status::Error("thesis: " + made.status().message());
  const std::unique_ptr<PixelPoseMeter> meter = std::move(made).value();
  const GainModel gm = o.nuisance_gains ? MakeGainModel(sys, o) : GainModel{};
  JointTally joint(nominal);
  PerRunTally per_run;
  double bound_sq = 0.0, gains_bound_sq = 0.0;
  PoseErrorStats poses;

  for (int trial = 0; trial < o.trials; ++trial) {
    Eigen::Vector3d truth = nominal;
    if (o.nominal_start) {
      const Eigen::Vector3d tol(kThesisTolR, kThesisTolR, kThesisTolD);
      for (int i = 0; i < 3; ++i) truth[i] += tol[i] * gauss(rng);
    }
    StatusOr<ThesisDesign> designed = MakeThesisDesign(sys, truth, o, R, meter.get(), rng);
    if (!designed.ok()) return Status::Error("thesis: " + designed.status().message());
    const ThesisDesign& d = *designed;
    Eigen::Vector3d guess = nominal;
    if (!o.nominal_start) {
      for (int i = 0; i < 3; ++i) guess[i] = truth[i] * (1.0 + o.guess_error * gauss(rng));
    }
    const Eigen::Matrix3d prior_cov =
        (o.guess_error * guess).array().square().matrix().asDiagonal();
    res.truth = truth;
    joint.SetTruth(truth);
    res.frames = static_cast<int>(d.all.size());
    res.duration_s = 0.0;
    for (const auto& run : d.runs) res.duration_s += NsToSeconds(run.t1 - run.t0);
    AddPoseErrors(d.pose_errors, &poses);
    AddCameraDays(d, &joint, &res);

    const double gate = o.pixels ? kPixelGateNis : 0.0;
    for (const auto& f : o.filters) {
      int gated = 0;
      joint.Record(f, RunFilter(sys, f, d, d.runs, guess, prior_cov, gate, &gated), &res);
      if (gate > 0.0) res.poses_gated[f] += gated;
      if (o.per_run) PerRunCalibrations(sys, f, d, truth, guess, prior_cov, gate, &per_run, &res);
    }
    BatchOptions bopt;
    bopt.prior = ParamPrior{guess, prior_cov};
    if (o.pixels) bopt.huber_scale = kPixelHuberScale;
    if (o.batch) joint.Record("batch", RunBatch(sys, d, guess, bopt), &res);
    if (o.nuisance_gains) {
      gains_bound_sq +=
          std::pow(FitWithGains(gm, o, d, truth, guess, prior_cov, bopt, &joint, &res), 2);
    }
    const double eb = BoundTrial(sys, o, d, truth, bopt, &per_run);
    bound_sq += eb * eb;
    res.bound_trial_nnde.push_back(eb);
  }
  joint.Finish(o.trials, &res);
  res.joint_bound_nnde_percent = 100.0 * std::sqrt(bound_sq / o.trials);
  res.joint_gains_bound_nnde_percent = 100.0 * std::sqrt(gains_bound_sq / o.trials);
  FinishPerRun(per_run, o, &res);
  FinishPoses(poses, &res);
  FinishCameraDays(&res);
  return res;
}

}  // namespace kincal
