#include "kincal/sim/simulator.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "kincal/angles.h"

namespace kincal {

bool FrameTimingOptions::IsValid(std::string* error) const {
  if (!(rate_hz > 0.0)) {
    *error = "rate_hz must be > 0";
    return false;
  }
  if (jitter_max_s < 0.0 || jitter_prob < 0.0 || jitter_prob > 1.0 || dropout_prob < 0.0 ||
      dropout_prob >= 1.0) {
    *error = "jitter_max_s >= 0, jitter_prob in [0,1], dropout_prob in [0,1) expected";
    return false;
  }
  return true;
}

std::vector<TimeNs> FrameTimes(TimeNs t0, TimeNs t1, const FrameTimingOptions& opt,
                               std::mt19937_64& rng, TimeNs* next) {
  std::string error;
  if (!opt.IsValid(&error)) throw std::invalid_argument("FrameTimes: " + error);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<TimeNs> times;
  double t = NsToSeconds(t0);
  const double end = NsToSeconds(t1);
  while (t < end) {
    if (unit(rng) >= opt.dropout_prob) times.push_back(SecondsToNs(t));
    double dt = 1.0 / opt.rate_hz;
    if (unit(rng) < opt.jitter_prob) dt += opt.jitter_max_s * unit(rng);
    t += dt;
  }
  if (next != nullptr) *next = SecondsToNs(t);
  return times;
}

void AppendConstant(ControlSignal* out, TimeNs t0, TimeNs t1, std::span<const double> u) {
  out->Append(t0, u);
  const std::array<double, kMaxControls> zero{};
  out->Append(t1, zero);
}

void AppendSmoothRandom(ControlSignal* out, TimeNs t0, TimeNs t1, std::span<const double> lo,
                        std::span<const double> hi, double min_period_s, double rate_hz,
                        std::mt19937_64& rng) {
  const int nc = out->num_channels();
  constexpr int kTerms = 4;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double freq[kMaxControls][kTerms], phase[kMaxControls][kTerms], amp[kMaxControls][kTerms];
  for (int c = 0; c < nc; ++c) {
    double total = 0.0;
    for (int k = 0; k < kTerms; ++k) {
      const double period = min_period_s * std::pow(10.0, unit(rng));
      freq[c][k] = 2.0 * std::numbers::pi / period;
      phase[c][k] = 2.0 * std::numbers::pi * unit(rng);
      amp[c][k] = 0.5 + unit(rng);
      total += amp[c][k];
    }
    for (int k = 0; k < kTerms; ++k) amp[c][k] /= total;  // sum of |terms| <= 1
  }
  const double dt = 1.0 / rate_hz;
  const double start = NsToSeconds(t0);
  for (double t = start; t < NsToSeconds(t1); t += dt) {
    std::array<double, kMaxControls> u{};
    for (int c = 0; c < nc; ++c) {
      double s = 0.0;
      for (int k = 0; k < kTerms; ++k)
        s += amp[c][k] * std::sin(freq[c][k] * (t - start) + phase[c][k]);
      const double mid = 0.5 * (lo[static_cast<size_t>(c)] + hi[static_cast<size_t>(c)]);
      const double half = 0.5 * (hi[static_cast<size_t>(c)] - lo[static_cast<size_t>(c)]);
      u[static_cast<size_t>(c)] = mid + half * s;
    }
    out->Append(SecondsToNs(t), u);
  }
  const std::array<double, kMaxControls> zero{};
  out->Append(t1, zero);
}

void AppendPiecewiseRandom(ControlSignal* out, TimeNs t0, TimeNs t1, std::span<const double> lo,
                           std::span<const double> hi, double min_hold_s, double max_hold_s,
                           std::mt19937_64& rng) {
  const int nc = out->num_channels();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double t = NsToSeconds(t0);
  while (t < NsToSeconds(t1)) {
    std::array<double, kMaxControls> u{};
    for (int c = 0; c < nc; ++c) {
      const size_t i = static_cast<size_t>(c);
      u[i] = lo[i] + (hi[i] - lo[i]) * unit(rng);
    }
    out->Append(SecondsToNs(t), u);
    t += min_hold_s + (max_hold_s - min_hold_s) * unit(rng);
  }
  const std::array<double, kMaxControls> zero{};
  out->Append(t1, zero);
}

std::vector<TrajectoryPoint> SimulateTruth(const System& truth, const StateVec& x0,
                                           const ControlSignal& realised,
                                           std::span<const TimeNs> times) {
  std::vector<TrajectoryPoint> out;
  out.reserve(times.size());
  StateVec x = x0;
  double t_prev = times.empty() ? 0.0 : realised.ToSeconds(times.front());
  for (TimeNs t : times) {
    const double ts = realised.ToSeconds(t);
    truth.Propagate(x.data(), x.data(), t_prev, ts, realised, static_cast<const double*>(nullptr));
    t_prev = ts;
    TrajectoryPoint p{t, x, Eigen::Vector3d::Zero()};
    truth.Measure(x.data(), p.target.data());
    p.target.z() = WrapAngle(p.target.z());
    out.push_back(p);
  }
  return out;
}

std::vector<PoseMeasurement> MeasurePoses(std::span<const TrajectoryPoint> truth,
                                          const Eigen::Matrix3d& R, int segment,
                                          std::mt19937_64& rng) {
  Eigen::LLT<Eigen::Matrix3d> llt(R);
  const Eigen::Matrix3d L = llt.matrixL();
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<PoseMeasurement> out;
  out.reserve(truth.size());
  for (const auto& p : truth) {
    // Drawn in a fixed sequence (the order in which constructor arguments are evaluated is
    // unspecified): last component first, the order GCC used, so earlier results stand.
    Eigen::Vector3d n;
    for (int i = 2; i >= 0; --i) n[i] = gauss(rng);
    PoseMeasurement m;
    m.t_ns = p.t_ns;
    m.z = p.target + L * n;
    m.z.z() = WrapAngle(m.z.z());
    m.R = R;
    m.segment = segment;
    out.push_back(m);
  }
  return out;
}

ControlSignal PerturbControls(const ControlSignal& commanded, std::span<const double> std_dev,
                              std::mt19937_64& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  ControlSignal out(commanded.num_channels(), commanded.origin_ns());
  for (size_t i = 0; i < commanded.size(); ++i) {
    auto v = commanded.ValuesAt(static_cast<int>(i));
    for (int c = 0; c < commanded.num_channels(); ++c) {
      const size_t k = static_cast<size_t>(c);
      if (k < std_dev.size()) v[k] += std_dev[k] * gauss(rng);
    }
    out.Append(commanded.ToNs(commanded.TimeAt(static_cast<int>(i))), v);
  }
  return out;
}

Eigen::Matrix3d PlanarPoseCovariance(double camera_height_m, double focal_px,
                                     std::span<const Eigen::Vector2d> markers,
                                     double centroid_sigma_px) {
  if (markers.size() < 2 || !(camera_height_m > 0.0) || !(focal_px > 0.0) ||
      !(centroid_sigma_px > 0.0)) {
    throw std::invalid_argument("PlanarPoseCovariance: need >= 2 markers and positive h, f, sigma");
  }
  // A nadir camera maps a floor displacement d to d * f / h pixels.
  const double sigma_m = centroid_sigma_px * camera_height_m / focal_px;
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  for (const auto& m : markers) {
    Eigen::Matrix<double, 2, 3> J;
    J << 1.0, 0.0, -m.y(), 0.0, 1.0, m.x();
    info += J.transpose() * J;
  }
  return info.inverse() * sigma_m * sigma_m;
}

}  // namespace kincal
