// A day's camera calibration in the realistic thesis world (src/sim/calibration_day.cc).
#include "sim/calibration_day.h"

#include <gtest/gtest.h>

#include <cmath>

#include "kincal/angles.h"

namespace kincal {
namespace {

// A nadir camera H above the floor, no distortion: the closed forms below hold for it.
ThesisVision Nadir() {
  ThesisVision v = ThesisTable63Vision();
  v.camera.k1 = v.camera.k2 = v.camera.p1 = v.camera.p2 = 0.0;
  v.camera.cx = 0.5 * (v.camera.width - 1);
  v.camera.cy = 0.5 * (v.camera.height - 1);
  v.floor.R_cf = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();  // looking down, z up
  v.floor.t_cf = Eigen::Vector3d(0.0, 0.0, 1.6);
  return v;
}

TEST(CalibrationDay, AFloorMapAgainstItselfIsExact) {
  const ThesisVision t = ThesisTable63Vision();
  const FloorMapError e = CompareFloorMaps(t, t);
  EXPECT_GT(e.points, 100);
  EXPECT_NEAR(e.scale, 0.0, 1e-9);
  EXPECT_NEAR(e.rms_m, 0.0, 1e-9);
  const Eigen::Vector3d pose(0.1, -0.05, 0.7);
  EXPECT_LT((MapPose(t, t, pose) - pose).norm(), 1e-9);
}

// A focal length 1 % long: a point imaged at u = f x / (H - h) is put at x / 1.01 on the
// plate's plane, a scale of 1/1.01 - 1, nothing bent. The floor moved and turned beside it
// is no scale at all (the similarity takes it): only where the workspace lies moves.
TEST(CalibrationDay, AFocalLengthErrorIsAScaleAndAMovedFloorIsNone) {
  const ThesisVision t = Nadir();
  ThesisVision longer = t;
  longer.camera.fx *= 1.01;
  longer.camera.fy *= 1.01;
  const FloorMapError e = CompareFloorMaps(t, longer);
  EXPECT_NEAR(e.scale, 1.0 / 1.01 - 1.0, 1e-9);
  EXPECT_NEAR(e.rms_m, 0.0, 1e-9);
  const Eigen::Vector3d p = MapPose(t, longer, Eigen::Vector3d(0.2, 0.1, 0.3));
  EXPECT_NEAR(p.x(), 0.2 / 1.01, 1e-9);
  EXPECT_NEAR(p.y(), 0.1 / 1.01, 1e-9);
  EXPECT_NEAR(p.z(), 0.3, 1e-9);
  ThesisVision moved = t;
  moved.floor.t_cf += moved.floor.R_cf * Eigen::Vector3d(0.01, -0.02, 0.0);
  const FloorMapError m = CompareFloorMaps(t, moved);
  EXPECT_NEAR(m.scale, 0.0, 1e-9);
  EXPECT_NEAR(m.rms_m, 0.0, 1e-9);
}

// The calibration's own sigma of its floor's scale against the scale errors it makes: over
// 16 days their RMS ratio is 1 within its sampling spread (about 0.18), and every day
// comes out a working camera (its focal length within 3 % of the truth's).
TEST(CalibrationDay, TheCalibrationsSigmaIsItsScaleError) {
  const ThesisVision truth = ThesisTable63Vision();
  CameraCalibrationErrors o;
  o.enabled = true;
  std::mt19937_64 rng(5);
  double z2 = 0.0, e2 = 0.0;
  constexpr int kDays = 16;
  for (int k = 0; k < kDays; ++k) {
    const StatusOr<CalibratedDay> calibrated = CalibrateDay(truth, o, 0.1414, rng);
    ASSERT_TRUE(calibrated.ok()) << calibrated.status().message();
    const CalibratedDay& day = calibrated.value();
    ASSERT_NEAR(day.vision.camera.fx / truth.camera.fx, 1.0, 0.03);
    ASSERT_GT(day.scale_sigma, 0.0);
    const FloorMapError e = CompareFloorMaps(truth, day.vision);
    z2 += std::pow(e.scale / day.scale_sigma, 2);
    e2 += e.scale * e.scale;
  }
  const double rms_z = std::sqrt(z2 / kDays);
  EXPECT_GT(rms_z, 0.5);
  EXPECT_LT(rms_z, 1.5);
  // The error is there to be seen: more than the poses' own noise could make.
  EXPECT_GT(std::sqrt(e2 / kDays), 2e-4);
}

TEST(CalibrationDay, OptionsAreChecked) {
  CameraCalibrationErrors o;
  std::string error;
  EXPECT_TRUE(o.IsValid(&error));
  o.runs_per_day = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("runs_per_day"), std::string::npos);
}

}  // namespace
}  // namespace kincal
