#include "kincal/vision/target.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace kincal::vision {

TargetLayout TargetLayout::Thesis() {
  TargetLayout t;
  t.name = "thesis";
  t.markers = {{0.045, 0.025}, {0.045, -0.025}, {-0.045, -0.025}, {-0.020, 0.025}};
  t.marker_radius_m = 0.008;
  return t;
}

bool TargetLayout::IsValid(std::string* error) const {
  if (markers.size() < 4) {
    *error = "a target needs at least 4 markers";
    return false;
  }
  if (!(marker_radius_m > 0.0) || !std::isfinite(marker_radius_m)) {
    *error = "marker_radius_m must be > 0";
    return false;
  }
  if (!(plate_size_m.array() > 0.0).all() || !plate_size_m.allFinite()) {
    *error = "plate_size_m must be two finite sizes > 0";
    return false;
  }
  for (size_t i = 0; i < markers.size(); ++i) {
    if (!markers[i].allFinite()) {
      *error = "marker " + std::to_string(i + 1) + ": its position must be finite";
      return false;
    }
  }
  for (size_t i = 0; i < markers.size(); ++i) {
    for (size_t j = i + 1; j < markers.size(); ++j) {
      if ((markers[i] - markers[j]).norm() < 2.0 * marker_radius_m) {
        *error = "markers " + std::to_string(i + 1) + " and " + std::to_string(j + 1) +
                 " overlap: centres closer than two radii (" +
                 std::to_string(2.0 * marker_radius_m) + " m)";
        return false;
      }
    }
  }
  return true;
}

namespace {

// Blur, vignetting, noise and 8-bit quantisation of a rendered radiance image. The noise
// comes from OpenCV's generator (a ziggurat normal, vectorised), seeded from `rng` so that a
// seed still fixes every frame; drawing 300,000 std::normal_distribution samples a frame
// made the simulated camera slower than the pipeline it feeds.
cv::Mat Finish(const CameraModel& cam, cv::Mat img, const RenderOptions& opt,
               std::mt19937_64& rng) {
  if (opt.blur_sigma_px > 0.0) cv::GaussianBlur(img, img, cv::Size(0, 0), opt.blur_sigma_px);
  if (opt.vignetting != 0.0) {
    const double rmax2 = 0.25 * (cam.width * cam.width + cam.height * cam.height);
    for (int v = 0; v < cam.height; ++v) {
      double* row = img.ptr<double>(v);
      const double dv2 = (v - cam.cy) * (v - cam.cy);
      for (int u = 0; u < cam.width; ++u) {
        row[u] *= 1.0 - opt.vignetting * ((u - cam.cx) * (u - cam.cx) + dv2) / rmax2;
      }
    }
  }
  if (opt.noise_sigma > 0.0) {
    cv::Mat noise(img.size(), CV_64FC1);
    cv::RNG noise_rng(static_cast<uint64_t>(rng()));
    noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, opt.noise_sigma);
    img += noise;
  }
  cv::Mat out8;
  img.convertTo(out8, CV_8UC1);  // rounds to nearest and saturates
  return out8;
}

}  // namespace

RenderedFrame RenderTarget(const CameraModel& cam, const Pose3& pose, const TargetLayout& layout,
                           const RenderOptions& opt, std::mt19937_64& rng) {
  cv::Mat img(cam.height, cam.width, CV_64FC1, cv::Scalar(opt.background));
  RenderedFrame out;
  const Eigen::Vector3d n = pose.R.col(2);  // plate normal in the camera frame
  const double d = n.dot(pose.t);           // plane: n . X = d
  const int s = std::max(1, opt.supersample);
  const double r2 = layout.marker_radius_m * layout.marker_radius_m;
  for (const auto& m : layout.markers) {
    const Eigen::Vector3d c = pose.R * Eigen::Vector3d(m.x(), m.y(), 0.0) + pose.t;
    out.centres.push_back(cam.Project(c));
    // Bounding box of the projected disk.
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (int k = 0; k < 32; ++k) {
      const double a = 2.0 * M_PI * k / 32.0;
      const Eigen::Vector3d b =
          pose.R * Eigen::Vector3d(m.x() + layout.marker_radius_m * std::cos(a),
                                   m.y() + layout.marker_radius_m * std::sin(a), 0.0) +
          pose.t;
      const Eigen::Vector2d p = cam.Project(b);
      u0 = std::min(u0, p.x());
      u1 = std::max(u1, p.x());
      v0 = std::min(v0, p.y());
      v1 = std::max(v1, p.y());
    }
    const int iu0 = std::max(0, static_cast<int>(std::floor(u0)) - 2);
    const int iu1 = std::min(cam.width - 1, static_cast<int>(std::ceil(u1)) + 2);
    const int iv0 = std::max(0, static_cast<int>(std::floor(v0)) - 2);
    const int iv1 = std::min(cam.height - 1, static_cast<int>(std::ceil(v1)) + 2);
    for (int v = iv0; v <= iv1; ++v) {
      for (int u = iu0; u <= iu1; ++u) {
        // Pixels well inside or well outside the disk need no supersampling: compare the
        // pixel centre's distance from the marker centre on the plate with a generous
        // bound on the pixel's footprint there.
        {
          const Eigen::Vector2d nn = cam.PixelToNormalized(Eigen::Vector2d(u, v));
          const Eigen::Vector3d ray(nn.x(), nn.y(), 1.0);
          const double cosine = std::abs(n.dot(ray)) / ray.norm();
          const double lambda = d / n.dot(ray);
          const Eigen::Vector3d X = pose.R.transpose() * (lambda * ray - pose.t);
          const double footprint = 2.0 * std::abs(lambda) * ray.norm() /
                                   (std::min(cam.fx, cam.fy) * std::max(cosine, 0.1));
          const double dist = (X.head<2>() - m).norm();
          if (dist > layout.marker_radius_m + footprint) continue;
          if (dist < layout.marker_radius_m - footprint) {
            img.at<double>(v, u) = opt.foreground;
            continue;
          }
        }
        int inside = 0;
        for (int sy = 0; sy < s; ++sy) {
          for (int sx = 0; sx < s; ++sx) {
            const Eigen::Vector2d px(u - 0.5 + (sx + 0.5) / s, v - 0.5 + (sy + 0.5) / s);
            const Eigen::Vector2d nn = cam.PixelToNormalized(px);
            const Eigen::Vector3d ray(nn.x(), nn.y(), 1.0);
            const double lambda = d / n.dot(ray);
            const Eigen::Vector3d X = pose.R.transpose() * (lambda * ray - pose.t);
            if ((X.head<2>() - m).squaredNorm() <= r2) ++inside;
          }
        }
        const double cover = static_cast<double>(inside) / (s * s);
        double& pix = img.at<double>(v, u);
        pix = pix * (1.0 - cover) + opt.foreground * cover;
      }
    }
  }
  if (!layout.dark_on_light) img = opt.background + opt.foreground - img;
  out.image = Finish(cam, img, opt, rng);
  return out;
}

RenderedFrame RenderChessboard(const CameraModel& cam, const Pose3& pose, int cols, int rows,
                               double pitch, const RenderOptions& opt, std::mt19937_64& rng) {
  cv::Mat img(cam.height, cam.width, CV_64FC1, cv::Scalar(opt.background));
  RenderedFrame out;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c)
      out.centres.push_back(
          cam.Project(pose.R * Eigen::Vector3d(c * pitch, r * pitch, 0) + pose.t));
  }
  const Eigen::Vector3d n = pose.R.col(2);
  const double d = n.dot(pose.t);
  const int s = std::max(1, opt.supersample / 2);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      int dark = 0, hits = 0;
      for (int sy = 0; sy < s; ++sy) {
        for (int sx = 0; sx < s; ++sx) {
          const Eigen::Vector2d nn =
              cam.PixelToNormalized({u - 0.5 + (sx + 0.5) / s, v - 0.5 + (sy + 0.5) / s});
          const Eigen::Vector3d ray(nn.x(), nn.y(), 1.0);
          const Eigen::Vector3d X = pose.R.transpose() * (d / n.dot(ray) * ray - pose.t);
          // Squares from -1 to cols (rows): a white margin around them.
          const double qx = X.x() / pitch + 1.0, qy = X.y() / pitch + 1.0;
          if (qx < 0 || qy < 0 || qx >= cols + 1 || qy >= rows + 1) continue;
          ++hits;
          if ((static_cast<int>(qx) + static_cast<int>(qy)) % 2 == 0) ++dark;
        }
      }
      if (hits > 0)
        img.at<double>(v, u) = opt.background + (opt.foreground - opt.background) * dark / (s * s);
    }
  }
  out.image = Finish(cam, img, opt, rng);
  return out;
}

}  // namespace kincal::vision
