// Synthetic calibration data with known truth, for tests, benchmarks and comparisons.
#pragma once

#include <random>
#include <vector>

#include "kincal/vision/calibration.h"

namespace kincal::vision {

// `n_views` views of a planar 9 x 6 grid of points (25 mm pitch) seen by `cam` from random
// poses about 0.7 m away (tilts up to ~30 deg), projected through the full distortion
// model and perturbed by Gaussian pixel noise of `noise_px`. Views with a point outside the
// image are redrawn. Deterministic for a given generator state.
std::vector<CalibrationView> SyntheticBoardViews(const CameraModel& cam, int n_views,
                                                 double noise_px, std::mt19937_64& rng);

}  // namespace kincal::vision
