#include "kincal/sim/thesis.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "kincal/check.h"

namespace kincal {
namespace {

// The realistic world's wheel gain error per wheel and speed band (1 sigma), tuned so that
// the simulated per-run scatter of the turn rate matches Table 6-5's 0.072 %
// (docs/thesis.md, "Tuning"). Only ThesisOptions::Realistic reads it.
constexpr double kRealisticGainSigma = 0.00038;

}  // namespace

// Table 6-4 (rad/s) and Table 6-5 (mm) of the thesis, transcribed.
const double kThesisControls[99][2] = {
    {2.3, 7.5},   {2.3, 12.9},  {2.3, 43.0},  {2.4, 37.7},  {2.5, 18.0},  {2.6, 22.7},
    {2.6, 27.8},  {2.9, 32.6},  {4.7, 9.8},   {5.0, 20.0},  {5.0, 24.6},  {5.0, 34.4},
    {5.0, 44.3},  {5.1, 14.8},  {5.1, 29.8},  {5.3, 39.3},  {7.1, 21.9},  {7.4, 12.4},
    {7.5, 17.1},  {7.6, 27.2},  {7.8, 2.6},   {9.9, 19.6},  {9.9, 29.1},  {9.9, 34.9},
    {10.0, 4.5},  {10.0, 44.9}, {2.1, 46.8},  {10.1, 24.4}, {10.5, 40.8}, {12.2, 2.2},
    {12.4, 27.0}, {12.6, 22.1}, {12.8, 6.6},  {1.2, 5.1},   {14.9, 35.2}, {14.9, 41.1},
    {15.0, 30.3}, {15.0, 44.6}, {15.1, 25.0}, {3.2, 20.2},  {15.6, 4.7},  {17.2, 33.0},
    {17.3, 2.2},  {17.6, 7.0},  {19.5, 2.9},  {19.6, 34.9}, {19.7, 37.1}, {19.8, 45.2},
    {19.9, 9.6},  {19.9, 40.2}, {32.2, 10.9}, {20.3, 5.0},  {17.5, 37.0}, {22.8, 2.6},
    {22.8, 7.0},  {24.5, 9.6},  {24.7, 4.7},  {21.8, 42.8}, {24.9, 14.8}, {22.9, 10.0},
    {6.1, 31.8},  {25.1, 44.4}, {25.5, 12.7}, {27.1, 2.0},  {27.3, 7.0},  {32.5, 7.4},
    {29.6, 4.7},  {29.6, 14.6}, {29.7, 12.3}, {29.8, 9.5},  {27.1, 10.8}, {25.2, 47.2},
    {15.5, 39.0}, {32.5, 2.3},  {34.7, 14.8}, {12.9, 32.6}, {5.0, 1.7},   {12.0, 36.6},
    {35.1, 5.1},  {35.1, 9.5},  {35.1, 19.0}, {33.1, 16.6}, {37.6, 1.6},  {39.4, 9.8},
    {39.6, 4.4},  {39.6, 14.6}, {39.7, 19.9}, {40.0, 22.7}, {38.0, 12.5}, {8.6, 32.5},
    {45.2, 22.1}, {43.1, 5.8},  {44.7, 9.8},  {44.8, 19.2}, {44.8, 15.0}, {44.9, 25.0},
    {17.0, 7.9},  {3.0, 6.0},   {45.3, 4.7},
};
const double kThesisEstimates[99][3] = {
    {30.970, 31.322, 148.130}, {30.788, 31.295, 148.240}, {31.670, 30.591, 144.610},
    {30.254, 31.243, 148.000}, {30.786, 31.375, 148.370}, {30.489, 31.303, 148.320},
    {30.417, 31.279, 148.110}, {30.454, 31.277, 148.250}, {31.005, 31.312, 148.040},
    {30.875, 31.316, 148.190}, {30.817, 31.281, 148.220}, {30.595, 31.328, 148.360},
    {30.298, 31.200, 147.890}, {30.951, 31.287, 148.100}, {30.670, 31.295, 148.350},
    {30.481, 31.216, 148.070}, {30.930, 31.284, 148.120}, {30.973, 31.267, 148.020},
    {30.983, 31.310, 148.070}, {30.911, 31.348, 148.210}, {31.024, 31.256, 148.190},
    {31.018, 31.328, 148.030}, {30.963, 31.324, 148.150}, {30.839, 31.287, 148.270},
    {30.971, 31.253, 148.110}, {30.544, 31.262, 148.450}, {30.743, 30.953, 146.460},
    {31.003, 31.313, 148.080}, {30.689, 31.237, 148.240}, {31.012, 31.026, 148.390},
    {30.987, 31.298, 148.040}, {31.010, 31.318, 148.020}, {31.039, 31.326, 148.080},
    {30.817, 31.292, 148.180}, {30.948, 31.293, 148.130}, {30.880, 31.246, 148.050},
    {30.995, 31.307, 148.040}, {30.846, 31.307, 148.400}, {30.991, 31.300, 148.030},
    {30.799, 31.328, 148.360}, {31.029, 31.238, 148.230}, {31.000, 31.318, 148.060},
    {31.069, 30.907, 148.560}, {31.008, 31.271, 148.140}, {31.032, 31.010, 148.500},
    {30.981, 31.290, 148.040}, {30.980, 31.306, 148.080}, {30.874, 31.309, 148.560},
    {30.992, 31.276, 148.090}, {30.946, 31.291, 148.130}, {30.976, 31.193, 148.150},
    {31.023, 31.146, 148.270}, {30.925, 31.269, 148.130}, {31.044, 30.795, 148.540},
    {31.027, 31.247, 148.230}, {30.996, 31.237, 148.140}, {31.028, 31.074, 148.390},
    {30.950, 31.304, 148.230}, {31.015, 31.307, 148.050}, {31.031, 31.307, 148.120},
    {30.744, 31.344, 148.410}, {30.995, 31.313, 148.110}, {31.012, 31.281, 148.090},
    {31.007, 30.523, 148.560}, {31.011, 31.266, 148.130}, {30.983, 31.046, 148.290},
    {31.038, 30.932, 148.390}, {31.017, 31.292, 148.090}, {30.955, 31.191, 148.160},
    {30.982, 31.153, 148.220}, {30.998, 31.251, 148.130}, {30.900, 31.239, 148.150},
    {30.893, 31.276, 148.230}, {31.001, 30.218, 148.460}, {30.985, 31.242, 148.190},
    {30.920, 31.292, 148.160}, {31.056, 31.246, 148.180}, {30.931, 31.338, 148.310},
    {30.985, 30.746, 148.380}, {31.043, 31.173, 148.370}, {31.024, 31.303, 148.100},
    {31.010, 31.284, 148.120}, {30.916, 29.899, 147.770}, {31.001, 31.016, 148.500},
    {30.985, 30.602, 148.290}, {30.993, 31.242, 148.180}, {31.005, 31.265, 148.200},
    {30.989, 31.267, 148.090}, {31.000, 31.156, 148.310}, {30.873, 31.312, 148.250},
    {30.994, 31.219, 148.320}, {30.959, 30.730, 148.180}, {30.977, 31.062, 148.120},
    {30.986, 31.170, 148.350}, {31.039, 31.114, 148.610}, {30.984, 31.250, 148.190},
    {31.007, 31.295, 148.100}, {30.975, 31.287, 148.040}, {30.864, 30.589, 147.750},
};

bool WheelRateErrors::IsValid(std::string* error) const {
  if (!(gain_sigma >= 0.0 && gain_sigma < 0.5) || !(band_width_rad_s > 0.0) ||
      !(command_step_rad_s >= 0.0) || !(max_rad_s >= 0.0)) {
    *error =
        "wheel: gain_sigma in [0, 0.5), band_width_rad_s > 0, command_step_rad_s >= 0 and "
        "max_rad_s >= 0 expected";
    return false;
  }
  return true;
}

double RealisedWheelRate(double w, int wheel, const WheelRateErrors& e,
                         const std::vector<std::array<double, 2>>& gains) {
  if (e.command_step_rad_s > 0.0) w = std::round(w / e.command_step_rad_s) * e.command_step_rad_s;
  if (e.max_rad_s > 0.0) w = std::clamp(w, -e.max_rad_s, e.max_rad_s);
  if (gains.empty()) return w;
  const size_t band =
      std::min(gains.size() - 1, static_cast<size_t>(std::abs(w) / e.band_width_rad_s));
  return w * (1.0 + gains[band][static_cast<size_t>(wheel)]);
}

namespace {

// The scalar settings of the camera and the timing (ThesisOptions::IsValid).
bool ValidMeasurement(const ThesisOptions& o, std::string* error) {
  if (!(o.guess_error > 0.0) || !(o.centroid_sigma_px > 0.0) || !(o.camera_height_m > 0.0) ||
      !(o.image_width_px > 0.0) || !(o.hfov_rad > 0.0 && o.hfov_rad < std::numbers::pi)) {
    *error =
        "guess_error, centroid_sigma_px, camera_height_m, image_width_px must be > 0 "
        "and hfov_rad in (0, pi)";
    return false;
  }
  if (!(o.stamp_step_s >= 0.0 && o.stamp_step_s < 0.5 / o.timing.rate_hz)) {
    *error = "stamp_step_s must be >= 0 and under half a frame period";
    return false;
  }
  return true;
}

}  // namespace

bool ThesisOptions::IsValid(std::string* error) const {
  if (runs < 1 || runs > 99) {
    *error = "runs must be in 1..99 (Table 6-4 has 99 experiments)";
    return false;
  }
  if (trials < 1) {
    *error = "trials must be >= 1";
    return false;
  }
  if (!ValidMeasurement(*this, error)) return false;
  if (frames_per_run < 0 || frames_per_run > 100000 || (pixels && frames_per_run == 0)) {
    *error = "frames_per_run must be in 0..100000, and > 0 with pixels";
    return false;
  }
  if (nuisance_gains && !(wheel.gain_sigma > 0.0)) {
    *error = "nuisance_gains needs wheel.gain_sigma > 0 (the gains' prior sigma)";
    return false;
  }
  return wheel.IsValid(error) && timing.IsValid(error) && (!pixels || pixel.IsValid(error));
}

// The realistic world (issue 18). gain_sigma is the one tuned value: the per-run scatter
// of the turn rate matched to Table 6-5's (docs/thesis.md, "Tuning"); it is used nowhere
// else.
ThesisOptions ThesisOptions::Realistic() {
  ThesisOptions o;
  o.pixels = true;
  o.frames_per_run = 128;  // the thesis's example run (§6.2.4)
  o.nominal_start = true;
  o.nuisance_gains = true;
  o.wheel.gain_sigma = kRealisticGainSigma;
  o.wheel.band_width_rad_s = 10.0;
  o.wheel.command_step_rad_s = 0.1;  // §7.3.2
  o.wheel.max_rad_s = 48.0;          // above the fastest command of Table 6-4 (47.2)
  o.stamp_step_s = 0.01;             // a 10 ms timer tick
  // The camera's own calibration error, calibrated anew each day of ten runs (issue 34).
  o.pixel.calibration.enabled = true;
  o.pixel.calibration.runs_per_day = 10;
  return o;
}

TableStats PerRunStats(const std::vector<Eigen::Vector3d>& est, const Eigen::Vector3d& truth) {
  TableStats s;
  const size_t n = est.size();
  if (n == 0) return s;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<double> dv(n), dw(n);
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d& a = est[k];
    const double wl = kThesisControls[k][0], wr = kThesisControls[k][1];
    const double v = 0.5 * (a[0] * wl + a[1] * wr), v0 = 0.5 * (truth[0] * wl + truth[1] * wr);
    const double w = (a[1] * wr - a[0] * wl) / a[2];
    const double w0 = (truth[1] * wr - truth[0] * wl) / truth[2];
    dv[k] = (v - v0) / v0;
    dw[k] = (w - w0) / w0;
    s.mean_nnde += Nnde(a, truth) / static_cast<double>(n);
    mean += a / static_cast<double>(n);
  }
  s.nnde_of_mean = Nnde(mean, truth);
  auto stdev = [n](const std::vector<double>& x) {
    double m = 0.0, q = 0.0;
    for (double v : x) m += v / static_cast<double>(n);
    for (double v : x) q += (v - m) * (v - m);
    return std::sqrt(q / std::max<double>(1.0, static_cast<double>(n) - 1.0));
  };
  s.speed_scatter = stdev(dv);
  s.turn_scatter = stdev(dw);
  return s;
}

TableStats ThesisTableStats() {
  std::vector<Eigen::Vector3d> est;
  for (const auto& row : kThesisEstimates)
    est.emplace_back(1e-3 * row[0], 1e-3 * row[1], 1e-3 * row[2]);
  return PerRunStats(est, Eigen::Vector3d(kThesisRL, kThesisRR, kThesisD));
}

double Nnde(const Eigen::VectorXd& est, const Eigen::VectorXd& truth) {
  return ((est - truth).array() / truth.array()).matrix().norm();
}

BoundRatio RatioToBound(const ThesisResult& r, const std::string& estimator) {
  BoundRatio out;
  const auto it = r.joint_trial_nnde.find(estimator);
  if (it == r.joint_trial_nnde.end() || it->second.size() != r.bound_trial_nnde.size() ||
      it->second.empty()) {
    return out;
  }
  const auto& e = it->second;
  const double n = static_cast<double>(e.size());
  double se2 = 0.0, sb2 = 0.0;
  for (size_t i = 0; i < e.size(); ++i) {
    se2 += e[i] * e[i];
    sb2 += r.bound_trial_nnde[i] * r.bound_trial_nnde[i];
  }
  const double mean_e2 = se2 / n, mean_b2 = sb2 / n;
  double var = 0.0;
  for (double v : e) var += std::pow(v * v - mean_e2, 2);
  var /= std::max(1.0, n - 1.0);
  const double half = 1.96 * std::sqrt(var / n) / mean_b2;
  out.ratio = mean_e2 / mean_b2;
  out.low = out.ratio - half;
  out.high = out.ratio + half;
  out.trials = static_cast<int>(e.size());
  return out;
}

double ExpectedNnde(const Eigen::MatrixXd& C, const Eigen::VectorXd& truth) {
  const Eigen::VectorXd w = truth.cwiseInverse();
  return std::sqrt((w.asDiagonal() * C * w.asDiagonal()).trace());
}

}  // namespace kincal
