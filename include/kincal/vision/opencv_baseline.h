// cv::calibrateCamera on the same views as CalibrateCamera, for side-by-side reports and
// tests. Header-only: include it only where opencv_calib3d is linked (the kincal tool and
// the tests), so that kincal::vision itself stays free of calib3d.
#pragma once

#include <opencv2/calib3d.hpp>
#include <vector>

#include "kincal/vision/calibration.h"

namespace kincal::vision {

struct OpenCvCalibration {
  CameraModel camera;
  double rms_px = 0.0;  // OpenCV's definition, as CalibrationResult::rms_px
};

// Planar views go in as they are (Z shifted to 0). OpenCV needs an initial guess for
// non-planar (rig) views: `guess` (e.g. our own result) is used then.
inline OpenCvCalibration CalibrateWithOpenCv(const std::vector<CalibrationView>& views,
                                             const CalibrationOptions& opt,
                                             const CameraModel& guess) {
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> img;
  bool planar = true;
  for (const auto& v : views) {
    obj.emplace_back();
    img.emplace_back();
    const double z0 = v.object.empty() ? 0.0 : v.object.front().z();
    for (size_t k = 0; k < v.object.size(); ++k) {
      planar = planar && v.object[k].z() == z0;
      obj.back().emplace_back(static_cast<float>(v.object[k].x()),
                              static_cast<float>(v.object[k].y()),
                              static_cast<float>(v.object[k].z() - z0));
      img.back().emplace_back(static_cast<float>(v.image[k].x()),
                              static_cast<float>(v.image[k].y()));
    }
  }
  cv::Mat K = (cv::Mat_<double>(3, 3) << guess.fx, 0, guess.cx, 0, guess.fy, guess.cy, 0, 0, 1);
  cv::Mat D = (cv::Mat_<double>(5, 1) << guess.k1, guess.k2, guess.p1, guess.p2, guess.k3);
  int flags = opt.use_k3 ? 0 : cv::CALIB_FIX_K3;
  if (!planar) flags |= cv::CALIB_USE_INTRINSIC_GUESS;
  std::vector<cv::Mat> rv, tv;
  OpenCvCalibration r;
  r.rms_px = cv::calibrateCamera(obj, img, cv::Size(opt.width, opt.height), K, D, rv, tv, flags);
  r.camera.width = opt.width;
  r.camera.height = opt.height;
  r.camera.fx = K.at<double>(0, 0);
  r.camera.fy = K.at<double>(1, 1);
  r.camera.cx = K.at<double>(0, 2);
  r.camera.cy = K.at<double>(1, 2);
  r.camera.k1 = D.at<double>(0);
  r.camera.k2 = D.at<double>(1);
  r.camera.p1 = D.at<double>(2);
  r.camera.p2 = D.at<double>(3);
  r.camera.k3 = D.total() > 4 ? D.at<double>(4) : 0.0;
  return r;
}

}  // namespace kincal::vision
