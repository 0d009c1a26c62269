// Telling which detection is which marker of a target layout (and which target is which,
// for several robots), and correcting each marker centre for perspective.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numeric>

#include "kincal/vision/markers.h"

namespace kincal::vision {
namespace {

// A target seen more obliquely than about 78 deg (singular value ratio below this) is not
// identified.
constexpr double kMinAffineSingularRatio = 0.2;

}  // namespace

bool IdentifyTarget(const CameraModel& cam, const TargetLayout& layout,
                    std::vector<Marker>* markers, double max_rms) {
  const size_t m = layout.markers.size();
  const size_t n = markers->size();
  if (n < m || n > 12) return false;
  std::vector<Eigen::Vector2d> norm;
  for (const auto& mk : *markers) norm.push_back(cam.PixelToNormalized(mk.centre_px));
  // Layout centred, for the similarity fit.
  Eigen::Vector2d lc = Eigen::Vector2d::Zero();
  for (const auto& p : layout.markers) lc += p;
  lc /= static_cast<double>(m);
  double best = 1e300;
  std::vector<size_t> best_assign;
  std::vector<size_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  // Every ordered choice of m detections (n <= 12, m = 4: at most 11880 candidates).
  std::vector<size_t> choice(m);
  std::vector<bool> used(n, false);
  std::function<void(size_t)> rec = [&](size_t depth) {
    if (depth == m) {
      // Affine least squares z = A w + b from the mirrored layout (the camera sees the
      // plate from its marked +z side, which mirrors the plate's (x, y) into the image's
      // (right, down) axes). Affine absorbs foreshortening of oblique views; det(A) > 0
      // keeps the handedness, which makes the asymmetric layout unambiguous.
      Eigen::Vector2d ic = Eigen::Vector2d::Zero();
      for (size_t i = 0; i < m; ++i) ic += norm[choice[i]];
      ic /= static_cast<double>(m);
      Eigen::Matrix2d WW = Eigen::Matrix2d::Zero(), ZW = Eigen::Matrix2d::Zero();
      for (size_t i = 0; i < m; ++i) {
        const Eigen::Vector2d w(layout.markers[i].x() - lc.x(), -(layout.markers[i].y() - lc.y()));
        const Eigen::Vector2d z = norm[choice[i]] - ic;
        WW += w * w.transpose();
        ZW += z * w.transpose();
      }
      const Eigen::Matrix2d A = ZW * WW.inverse();
      if (A.determinant() <= 0) return;
      Eigen::JacobiSVD<Eigen::Matrix2d> svd(A);
      if (svd.singularValues()[1] < kMinAffineSingularRatio * svd.singularValues()[0]) return;
      double res = 0, scale = 0;
      for (size_t i = 0; i < m; ++i) {
        const Eigen::Vector2d w(layout.markers[i].x() - lc.x(), -(layout.markers[i].y() - lc.y()));
        const Eigen::Vector2d z = norm[choice[i]] - ic;
        res += (z - A * w).squaredNorm();
        scale += z.squaredNorm();
      }
      const double rel = std::sqrt(res / std::max(scale, 1e-300));
      if (rel < best) {
        best = rel;
        best_assign = choice;
      }
      return;
    }
    for (size_t j = 0; j < n; ++j) {
      if (used[j]) continue;
      used[j] = true;
      choice[depth] = j;
      rec(depth + 1);
      used[j] = false;
    }
  };
  rec(0);
  if (best > max_rms) return false;
  for (auto& mk : *markers) mk.id = -1;
  for (size_t i = 0; i < m; ++i) (*markers)[best_assign[i]].id = static_cast<int>(i);
  return true;
}

std::vector<std::vector<Marker>> IdentifyTargets(const CameraModel& cam,
                                                 const std::vector<TargetLayout>& layouts,
                                                 const std::vector<Marker>& detections,
                                                 double max_rms) {
  std::vector<std::vector<Marker>> out(layouts.size());
  std::vector<Marker> pool = detections;
  // Layouts with more markers first: they are the most constrained.
  std::vector<size_t> order(layouts.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return layouts[a].markers.size() > layouts[b].markers.size();
  });
  for (size_t li : order) {
    std::vector<Marker> trial = pool;
    if (!IdentifyTarget(cam, layouts[li], &trial, max_rms)) continue;
    std::vector<Marker> rest;
    for (const auto& m : trial) {
      if (m.id >= 0) {
        out[li].push_back(m);
      } else {
        rest.push_back(m);
      }
    }
    std::sort(out[li].begin(), out[li].end(),
              [](const Marker& a, const Marker& b) { return a.id < b.id; });
    pool = rest;
  }
  return out;
}

double CorrectPerspectiveBias(const CameraModel& cam, const Pose3& pose, const TargetLayout& layout,
                              std::vector<Marker>* markers) {
  double largest = 0.0;
  for (auto& m : *markers) {
    if (m.id < 0 || m.id >= static_cast<int>(layout.markers.size())) continue;
    const Eigen::Vector2d c = layout.markers[static_cast<size_t>(m.id)];
    const Eigen::Vector2d centre =
        cam.Project(pose.R * Eigen::Vector3d(c.x(), c.y(), 0.0) + pose.t);
    // Area centroid of the projected boundary polygon.
    constexpr int kN = 96;
    std::array<Eigen::Vector2d, kN> b;
    for (int k = 0; k < kN; ++k) {
      const double a = 2.0 * M_PI * k / kN;
      const Eigen::Vector3d p(c.x() + layout.marker_radius_m * std::cos(a),
                              c.y() + layout.marker_radius_m * std::sin(a), 0.0);
      b[static_cast<size_t>(k)] = cam.Project(pose.R * p + pose.t);
    }
    double area = 0;
    Eigen::Vector2d cen = Eigen::Vector2d::Zero();
    for (int k = 0; k < kN; ++k) {
      const auto& p0 = b[static_cast<size_t>(k)];
      const auto& p1 = b[static_cast<size_t>((k + 1) % kN)];
      const double cross = p0.x() * p1.y() - p1.x() * p0.y();
      area += cross;
      cen += (p0 + p1) * cross;
    }
    if (std::abs(area) < 1e-12) continue;
    cen /= 3.0 * area;
    const Eigen::Vector2d bias = cen - centre;
    m.centre_px -= bias;
    largest = std::max(largest, bias.norm());
  }
  return largest;
}

}  // namespace kincal::vision
