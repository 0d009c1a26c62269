#include "kincal/plan/workspace.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace kincal {
namespace {

class Arena final : public Workspace {
 public:
  Arena(double x0, double y0, double x1, double y1) : lo_(x0, y0), hi_(x1, y1) {}
  bool Contains(const Eigen::Vector3d& p) const override {
    return p.x() >= lo_.x() && p.x() <= hi_.x() && p.y() >= lo_.y() && p.y() <= hi_.y();
  }
  Eigen::Vector2d Centre() const override { return 0.5 * (lo_ + hi_); }
  double Size() const override { return (hi_ - lo_).minCoeff(); }
  std::string Describe() const override {
    std::ostringstream s;
    s << "arena [" << lo_.x() << ", " << hi_.x() << "] x [" << lo_.y() << ", " << hi_.y() << "] m";
    return s.str();
  }

 private:
  Eigen::Vector2d lo_, hi_;
};

class CameraView final : public Workspace {
 public:
  CameraView(const vision::CameraModel& camera, const vision::FloorExtrinsics& floor,
             const vision::TargetLayout& layout, double height, double margin)
      : camera_(camera), floor_(floor), layout_(layout), height_(height), margin_(margin) {
    const Eigen::Matrix3d Rfc = floor.R_cf.transpose();
    const Eigen::Vector3d c = -Rfc * floor.t_cf, axis = Rfc.col(2);
    centre_ = (c + axis * ((height - c.z()) / axis.z())).head<2>();
    // Half-width through the centre: the shortest of eight rays to the edge of the view.
    size_ = 1e9;
    for (int k = 0; k < 8; ++k) {
      const double a = k * std::numbers::pi / 4.0;
      const Eigen::Vector2d dir(std::cos(a), std::sin(a));
      double lo = 0.0, hi = 10.0;
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Eigen::Vector2d q = centre_ + mid * dir;
        (Contains(Eigen::Vector3d(q.x(), q.y(), 0.0)) ? lo : hi) = mid;
      }
      size_ = std::min(size_, 2.0 * lo);
    }
  }
  bool Contains(const Eigen::Vector3d& p) const override {
    const vision::Pose3 pose = vision::CameraPoseOnFloor(floor_, p, height_);
    const double r = layout_.marker_radius_m;
    for (const auto& m : layout_.markers) {
      for (const Eigen::Vector2d& off :
           {Eigen::Vector2d(0, 0), Eigen::Vector2d(r, 0), Eigen::Vector2d(-r, 0),
            Eigen::Vector2d(0, r), Eigen::Vector2d(0, -r)}) {
        const Eigen::Vector3d q =
            pose.R * Eigen::Vector3d(m.x() + off.x(), m.y() + off.y(), 0.0) + pose.t;
        if (!(q.z() > 0.0)) return false;
        const Eigen::Vector2d px = camera_.Project(q);
        if (!(px.x() >= margin_ && px.y() >= margin_ && px.x() <= camera_.width - 1 - margin_ &&
              px.y() <= camera_.height - 1 - margin_)) {
          return false;
        }
      }
    }
    return true;
  }
  Eigen::Vector2d Centre() const override { return centre_; }
  double Size() const override { return size_; }
  std::string Describe() const override {
    std::ostringstream s;
    s << "camera view (" << camera_.width << "x" << camera_.height << ", margin " << margin_
      << " px), centre (" << centre_.x() << ", " << centre_.y() << ") m, " << size_ << " m across";
    return s.str();
  }

 private:
  vision::CameraModel camera_;
  vision::FloorExtrinsics floor_;
  vision::TargetLayout layout_;
  double height_, margin_;
  Eigen::Vector2d centre_;
  double size_ = 0.0;
};

}  // namespace

std::unique_ptr<Workspace> MakeArena(double x0, double y0, double x1, double y1) {
  return std::make_unique<Arena>(x0, y0, x1, y1);
}

std::unique_ptr<Workspace> MakeCameraView(const vision::CameraModel& camera,
                                          const vision::FloorExtrinsics& floor,
                                          const vision::TargetLayout& layout,
                                          double target_height_m, double margin_px) {
  return std::make_unique<CameraView>(camera, floor, layout, target_height_m, margin_px);
}

}  // namespace kincal
