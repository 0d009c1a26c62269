// The sub-pixel centre of a detected blob (markers.cc): intensity-weighted over its box
// grown by two pixels. Private to the vision layer.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "vision/labels.h"

namespace kincal::vision {

// The marker level is the darkest (brightest) quarter of the foreground pixels inside the
// blob's box; the background level is the median of the window's border. A pixel's weight
// is its depth below the background in units of the contrast, capped at 1 but not floored
// at 0: noise on the background pixels then averages out, where clipping it at 0 would pull
// the centre towards the middle of the window, by up to a fifth of the noise's own scatter
// (Markers.HeavyNoiseScattersTheCentreWithoutBiasingIt). *weight is the sum of the
// weights (the marker's area in pixels). False without contrast.
bool WeightedCentre(const cv::Mat& view, const Blob& b, int thr, bool dark_on_light,
                    Eigen::Vector2d* centre, double* weight);

}  // namespace kincal::vision
