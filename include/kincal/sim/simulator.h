// Simulator: control profiles, true trajectories and noisy pose measurements.
//
// The truth is any System (a model plus effects the estimator may not know about); the
// logged controls are the commands, the motion follows the realised controls. Camera
// frames arrive at a nominal rate with random stalls (capture jitter) and dropouts; each
// carries an exact timestamp. Everything is driven by one seeded std::mt19937_64.
#pragma once

#include <Eigen/Core>
#include <random>
#include <span>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/estimation/batch.h"
#include "kincal/system.h"
#include "kincal/time.h"

namespace kincal {

struct FrameTimingOptions {
  double rate_hz = 6.0;       // nominal frame rate
  double jitter_max_s = 0.0;  // a stalled frame arrives up to this much later
  double jitter_prob = 0.0;   // probability that a frame interval stalls
  double dropout_prob = 0.0;  // probability that a frame is lost
  bool IsValid(std::string* error) const;
};

// Frame timestamps from t0 while the running sum of intervals (in seconds) is below t1 (a
// sum a rounding error short of t1 gives a last frame at t1): intervals of 1/rate, plus
// U(0, jitter_max) with
// probability jitter_prob; frames dropped with probability dropout_prob. `next`, when given,
// receives the time of the frame after the last: where a following call continues the stream.
std::vector<TimeNs> FrameTimes(TimeNs t0, TimeNs t1, const FrameTimingOptions& opt,
                               std::mt19937_64& rng, TimeNs* next = nullptr);

// Control profiles (commanded). All append samples to `out` in [t0, t1] and leave a zero
// sample at t1 (the robot stops).
void AppendConstant(ControlSignal* out, TimeNs t0, TimeNs t1, std::span<const double> u);
// Smooth random commands: each channel is a sum of random sinusoids with periods between
// min_period_s and 10 * min_period_s, spanning [lo, hi], sampled at rate_hz.
void AppendSmoothRandom(ControlSignal* out, TimeNs t0, TimeNs t1, std::span<const double> lo,
                        std::span<const double> hi, double min_period_s, double rate_hz,
                        std::mt19937_64& rng);
// Piecewise constant: random levels in [lo, hi], each held for a duration drawn in
// [min_hold_s, max_hold_s].
void AppendPiecewiseRandom(ControlSignal* out, TimeNs t0, TimeNs t1, std::span<const double> lo,
                           std::span<const double> hi, double min_hold_s, double max_hold_s,
                           std::mt19937_64& rng);

struct TrajectoryPoint {
  TimeNs t_ns;
  StateVec x;              // true augmented state (reference pose, params, effect states)
  Eigen::Vector3d target;  // true target pose (what a perfect camera would measure)
};

// True states at the given times, starting from x0 at times.front(); `realised` drives the
// motion (use the commanded signal when there is no control noise).
std::vector<TrajectoryPoint> SimulateTruth(const System& truth, const StateVec& x0,
                                           const ControlSignal& realised,
                                           std::span<const TimeNs> times);

// Noisy measurements of the true target poses: z = target + N(0, R), heading wrapped.
std::vector<PoseMeasurement> MeasurePoses(std::span<const TrajectoryPoint> truth,
                                          const Eigen::Matrix3d& R, int segment,
                                          std::mt19937_64& rng);

// Commanded signal plus white noise of the given std per channel on every sample: the
// realised controls of a robot whose actuators do not follow exactly.
ControlSignal PerturbControls(const ControlSignal& commanded, std::span<const double> std_dev,
                              std::mt19937_64& rng);

// Covariance of a planar pose (x, y, theta) measured by a nadir camera at height h (m)
// with focal length f (px) from markers at the given target-frame positions (m, origin at
// their centroid) whose centres each have isotropic noise sigma_px.
Eigen::Matrix3d PlanarPoseCovariance(double camera_height_m, double focal_px,
                                     std::span<const Eigen::Vector2d> markers,
                                     double centroid_sigma_px);

}  // namespace kincal
