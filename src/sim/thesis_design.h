// The runs of one thesis trial: controls (requested and realised), frame times, start
// poses and pose measurements, for the idealised and the realistic world (kincal/sim/thesis.h).
#pragma once

#include <Eigen/Core>
#include <array>
#include <random>
#include <vector>

#include "kincal/estimation/batch.h"
#include "kincal/sim/thesis.h"
#include "kincal/sim/thesis_vision.h"
#include "sim/calibration_day.h"

namespace kincal {

struct ThesisRun {
  int index = 0;  // 0-based row of Table 6-4
  TimeNs t0 = 0, t1 = 0;
  std::vector<PoseMeasurement> meas;
  Eigen::Vector3d start_pose = Eigen::Vector3d::Zero();
};

// Pose errors against the truth of the measurements made through pixels.
struct PoseErrorStats {
  int frames = 0, lost = 0, gross = 0;  // gross: NEES > 100, not in the sums
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  double sum_nees = 0.0;
};

struct ThesisDesign {
  // Each experiment day's floor map against the truth (the camera's calibration error),
  // the scale's 1-sigma the calibration gives, and the day's share of the runs.
  struct CameraDay {
    FloorMapError error;
    double scale_sigma = 0.0;
    int runs = 0;
  };
  std::vector<CameraDay> days;
  ControlSignal controls{2, 0};  // requested: what the estimators see
  ControlSignal realised{2, 0};  // what the wheels did
  std::vector<ThesisRun> runs;
  std::vector<PoseMeasurement> all;
  std::vector<Eigen::Vector3d> starts;
  // The look-up table's gain errors per speed band (left, right); empty when none.
  std::vector<std::array<double, 2>> gains;
  PoseErrorStats pose_errors;
};

// `params` is the true robot; `R` the pose covariance of the Gaussian measurements (unused
// with a meter); `meter` measures through pixels when given. An error when a day's camera
// calibration fails (PixelPoseMeter::BeginDay), naming the experiment.
StatusOr<ThesisDesign> MakeThesisDesign(const System& truth, const Eigen::Vector3d& params,
                                        const ThesisOptions& o, const Eigen::Matrix3d& R,
                                        PixelPoseMeter* meter, std::mt19937_64& rng);

}  // namespace kincal
