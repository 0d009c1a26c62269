// Where a planned motion may take the target: a rectangle on the floor, or the part of
// the floor a camera sees the whole target in.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "kincal/vision/camera.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/target.h"

namespace kincal {

class Workspace {
 public:
  virtual ~Workspace() = default;
  // Whether the target at measured floor pose (x, y, theta) is inside.
  virtual bool Contains(const Eigen::Vector3d& pose) const = 0;
  // Where a plan starts: the middle of the workspace (m).
  virtual Eigen::Vector2d Centre() const = 0;
  // The smallest width of the workspace through its centre (m): the scale the usual
  // motions are drawn to.
  virtual double Size() const = 0;
  virtual std::string Describe() const = 0;
};

// x0 < x1, y0 < y1 (m); the target's origin must stay inside.
std::unique_ptr<Workspace> MakeArena(double x0, double y0, double x1, double y1);

// Every marker (its centre and its rim) imaged at least `margin_px` inside the frame,
// target plane `target_height_m` above the floor. Centre: where the optical axis meets
// the target plane.
std::unique_ptr<Workspace> MakeCameraView(const vision::CameraModel& camera,
                                          const vision::FloorExtrinsics& floor,
                                          const vision::TargetLayout& layout,
                                          double target_height_m, double margin_px);

}  // namespace kincal
