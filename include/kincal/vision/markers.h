// Circular marker detection with sub-pixel centres, and target identification.
//
// Background flattening (whole-frame searches: vignetting and uneven light divided out),
// threshold (Otsu within the search region unless fixed), connected components, shape
// tests (area, circularity from second moments, fill ratio), then an intensity-weighted
// centre: every pixel around a blob counts by how much of it the marker covers, estimated
// from its grey level between the local background and the marker's own level, so
// partially covered edge pixels place the centre to a small fraction of a pixel.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "kincal/vision/camera.h"
#include "kincal/vision/target.h"

namespace kincal::vision {

struct DetectorOptions {
  bool dark_on_light = true;
  int threshold = -1;  // grey level; -1: Otsu within the search region
  int min_area_px = 12;
  int max_area_px = 40000;
  double min_circularity = 0.6;  // minor/major axis ratio of the blob's ellipse
  double min_fill = 0.6;         // blob area / area of that ellipse
  int min_contrast = 20;         // Otsu: grey levels between the classes, else no markers
  // Large search regions (a whole frame): estimate the floor's brightness per tile (a
  // high quantile for dark markers, a low one for bright markers, the brightest (darkest)
  // of each tile's neighbours so that a marker filling a tile does not count), interpolate
  // it, and divide it out before the threshold: vignetting and uneven light are
  // multiplicative and vanish. Small regions (tracking) are flat enough without.
  bool flatten_background = true;
  int background_tile_px = 64;
  bool IsValid(std::string* error) const;
};

struct Marker {
  Eigen::Vector2d centre_px;  // intensity-weighted centre (distorted image), px
  double area_px = 0.0;
  double diameter_px = 0.0;
  int id = -1;  // index in the target layout once identified
};

struct Rejected {
  Eigen::Vector2d centre_px;
  std::string reason;
};

// Detects markers in `roi` (whole image if empty) of an 8-bit grey image.
std::vector<Marker> DetectMarkers(const cv::Mat& grey, const DetectorOptions& opt,
                                  cv::Rect roi = {}, std::vector<Rejected>* rejected = nullptr);

// Assigns layout ids: among the detections, the set of layout.markers.size() markers and
// the correspondence whose affine fit (in undistorted normalised coordinates, handedness
// kept) leaves the smallest residual. Returns false when no assignment fits within `max_rms`
// (relative to the target's size in the image).
bool IdentifyTarget(const CameraModel& cam, const TargetLayout& layout,
                    std::vector<Marker>* markers, double max_rms = 0.05);

// Several targets (several robots) in one view, told apart by their layouts: each layout
// in turn takes the best-fitting unassigned detections. Returns, per layout, its markers
// (ids set, sorted by id) or an empty vector when that target is not in view.
std::vector<std::vector<Marker>> IdentifyTargets(const CameraModel& cam,
                                                 const std::vector<TargetLayout>& layouts,
                                                 const std::vector<Marker>& detections,
                                                 double max_rms = 0.05);

// The centre of a projected circle is not the centre of its image (an ellipse, further
// bent by distortion): given the target pose, moves each identified marker's measured
// centre by (projected circle centre - area centroid of the projected disk). Returns the
// largest correction applied, px.
double CorrectPerspectiveBias(const CameraModel& cam, const Pose3& pose, const TargetLayout& layout,
                              std::vector<Marker>* markers);

// Tracking: searches a region around the last target first and falls back to the whole
// frame when the target is not found there.
class MarkerTracker {
 public:
  MarkerTracker(CameraModel cam, TargetLayout layout, DetectorOptions opt, int margin_px = 24)
      : cam_(std::move(cam)), layout_(std::move(layout)), opt_(opt), margin_(margin_px) {}
  // Identified markers (ids set) or an empty vector when the target is not in the frame.
  std::vector<Marker> Track(const cv::Mat& grey);
  bool last_was_full_frame() const { return full_frame_; }
  int64_t full_frame_searches() const { return full_searches_; }

 private:
  CameraModel cam_;
  TargetLayout layout_;
  DetectorOptions opt_;
  int margin_;
  cv::Rect roi_;
  bool full_frame_ = true;
  int64_t full_searches_ = 0;
};

}  // namespace kincal::vision
