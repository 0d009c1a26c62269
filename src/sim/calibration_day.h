// The thesis camera's own calibration error, one experiment day at a time (issue 34).
//
// Each day the camera and the floor are calibrated anew (§6.2.2: the calibration target
// is placed in the workspace and cameraCal.m run): a planar board of the target's 20 mm
// markers, imaged lying on the floor at the workspace origin (that view gives the floor)
// and held tilted four ways (which separate the focal length from the distance), its
// marker centres carrying the pose measurement's own noise, calibrated with kincal's
// camera calibration (intrinsics, Heikkilä's k1, k2, p1, p2, every view's pose). The
// result is a draw from the calibration's error distribution, with its correlations: the
// day's poses are solved with it while the images are made by the true camera, so it
// scales and bends the floor the same way for every run of that day.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <random>
#include <string>

#include "kincal/sim/thesis_vision.h"

namespace kincal {

// How one calibration maps the floor against another (the truth, or the calibration
// itself), over the points of the target's plane the camera sees (a 5 cm grid): each
// point imaged through `reference` and brought back onto the plane through `calibrated`.
// Fitted with a similarity (where the floor's origin and axes lie does not matter to the
// robot's lengths): scale, its error (a fraction, 0: none); rms_m, the position error
// the similarity leaves (the bend).
struct FloorMapError {
  double scale = 0.0;
  double rms_m = 0.0;
  int points = 0;
};
FloorMapError CompareFloorMaps(const ThesisVision& reference, const ThesisVision& calibrated);

// Where a pose solver working with `calibrated` puts a target that `reference` images at
// floor pose (x, y, theta): its origin and a point 0.1 m along its heading, each imaged on
// the plate's plane and brought back through `calibrated`. What a noise-free measurement
// gives on a day with that calibration (pose errors are judged against it). The pose
// itself where a camera's distortion folds (never inside the workspace).
Eigen::Vector3d MapPose(const ThesisVision& reference, const ThesisVision& calibrated,
                        const Eigen::Vector3d& pose);

// One day's calibration of `truth` (camera and floor) from views whose centres scatter by
// `centroid_sigma_px` per axis, and what the calibration itself says of its floor's scale:
// its 1-sigma from a parametric bootstrap (the views re-imaged through the calibration with
// the noise its residuals show, and calibrated again; no truth used). An error when a
// calibration fails (a board out of view, or centres too noisy to calibrate from), naming
// which.
struct CalibratedDay {
  ThesisVision vision;
  double scale_sigma = 0.0;
};
StatusOr<CalibratedDay> CalibrateDay(const ThesisVision& truth, const CameraCalibrationErrors& o,
                                     double centroid_sigma_px, std::mt19937_64& rng);

}  // namespace kincal
