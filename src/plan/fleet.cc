#include "plan/fleet.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "kincal/angles.h"

namespace kincal::plan_internal {
namespace {

constexpr double kNonlinearMargin = 1.2;

}  // namespace

std::vector<Eigen::VectorXd> RobotsWithinPrior(const Eigen::VectorXd& params,
                                               const Eigen::MatrixXd& prior_cov, double k) {
  std::vector<Eigen::VectorXd> out = {params};
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(prior_cov);
  for (Eigen::Index i = 0; i < params.size(); ++i) {
    const Eigen::VectorXd d =
        k * std::sqrt(std::max(eig.eigenvalues()[i], 0.0)) * eig.eigenvectors().col(i);
    out.push_back(params + d);
    out.push_back(params - d);
  }
  return out;
}

// Whether every robot within the k-sigma ellipsoid of the prior keeps its target inside.
// The axis robots are checked as they are (nonlinear); the ellipsoid between them through
// the pose's spread they imply: half the difference of each pair is the pose's change
// along that axis, so the poses within the ellipsoid fill, to first order, the ellipsoid
// of covariance D D' about the nominal pose; its six extreme points, pushed a fifth
// further out for what the first order misses over a long open-loop run, are checked too.
bool FleetInside(const System& sys, const Workspace& ws, const Fleet& f) {
  Eigen::Vector3d z0;
  sys.Measure(f.x[0].data(), z0.data());
  if (!ws.Contains(z0)) return false;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t k = 1; k + 1 < f.x.size(); k += 2) {
    Eigen::Vector3d zp, zm;
    sys.Measure(f.x[k].data(), zp.data());
    sys.Measure(f.x[k + 1].data(), zm.data());
    if (!ws.Contains(zp) || !ws.Contains(zm)) return false;
    Eigen::Vector3d d = 0.5 * (zp - zm);
    d.z() = WrapAngle(d.z());
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d a = kNonlinearMargin * std::sqrt(std::max(eig.eigenvalues()[i], 0.0)) *
                              eig.eigenvectors().col(i);
    if (!ws.Contains(z0 + a) || !ws.Contains(z0 - a)) return false;
  }
  return true;
}

// Whether every robot of the fleet (the design point and the axis robots) keeps its
// target inside, without the poses between them.
bool CornersInside(const System& sys, const Workspace& ws, const Fleet& f) {
  for (const auto& x : f.x) {
    Eigen::Vector3d z;
    sys.Measure(x.data(), z.data());
    if (!ws.Contains(z)) return false;
  }
  return true;
}

// Drives the fleet to t1, checking every `check_s` with `inside`; false if any target left
// (with `stop_early`, as soon as one does, leaving the fleet there).
bool DriveFleet(const System& sys, const ControlSignal& u, const Workspace& ws, double t1,
                double check_s, bool stop_early, Fleet* f, FleetCheck inside_check) {
  bool inside = true;
  while (f->t_s < t1 - 1e-12) {
    const double t = std::min(t1, f->t_s + check_s);
    for (auto& x : f->x) {
      sys.Propagate(x.data(), x.data(), f->t_s, t, u, static_cast<const double*>(nullptr));
    }
    f->t_s = t;
    if (!inside_check(sys, ws, *f)) {
      inside = false;
      if (stop_early) return false;
    }
  }
  return inside;
}

// The fleet at the start pose, at rest.
Fleet FleetAtStart(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Eigen::Vector3d& start,
                   const PlanOptions& o, const ControlSignal& u) {
  Fleet fleet;
  for (const auto& p : RobotsWithinPrior(params, prior_cov, o.prior_sigmas)) {
    fleet.x.push_back(sys.MakeState(start.x(), start.y(), start.z(), p, u, 0.0));
  }
  return fleet;
}

bool FleetStaysInside(const System& sys, const Eigen::VectorXd& params,
                      const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                      const ControlSignal& u, FleetCheck inside_check) {
  // At rest at the start, as the planner's fleet starts (not with its effects' states at
  // the first commands: a lag that had already caught up with them).
  Fleet fleet = FleetAtStart(sys, params, prior_cov, StartPose(ws, o), o,
                             ControlSignal(sys.num_controls(), 0));
  const double end_s = u.size() == 0 ? 0.0 : u.TimeAt(static_cast<int>(u.size()) - 1);
  return inside_check(sys, ws, fleet) &&
         DriveFleet(sys, u, ws, end_s, kFleetCheckS, true, &fleet, inside_check);
}

}  // namespace kincal::plan_internal
