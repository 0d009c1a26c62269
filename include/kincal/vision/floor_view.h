// The part of the floor a camera sees: the image border's rays met with a horizontal plane
// (the plane of the target's markers, `height_m` above the floor), in the floor frame.
// For people (kincal view's map), not for the estimator.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "kincal/vision/camera.h"
#include "kincal/vision/pose.h"

namespace kincal::vision {

// `per_side` points along each image edge, clockwise from the top-left pixel corner,
// each the floor point (x, y) its ray meets; rays that never meet the plane (above the
// horizon) are left out, so a camera that sees no floor gives an empty polygon.
std::vector<Eigen::Vector2d> FloorSeen(const CameraModel& camera, const FloorExtrinsics& floor,
                                       double height_m, int per_side = 8);

// The target's frame in the image: the pixels of its origin and of the ends of its x and y
// axes (each `length_m` long) for its pose (x, y, theta) on the plane z = height_m. False
// when a point is not in front of the camera.
bool TargetAxesInImage(const CameraModel& camera, const FloorExtrinsics& floor, double height_m,
                       const Eigen::Vector3d& xytheta, double length_m,
                       std::array<Eigen::Vector2d, 3>* px);

}  // namespace kincal::vision
