// kincal target / detect / floorcal: a printable target, a look at what the detector
// finds, and the camera's pose above the floor.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "board.h"
#include "commands.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/setup_files.h"
#include "options.h"

namespace kincal::app {
namespace {

// An image in the format its extension names (.png, .jpg, ...), written whole or not at all.
Status WriteImage(const std::string& path, const cv::Mat& image) {
  std::vector<uint8_t> bytes;
  const std::string ext = std::filesystem::path(path).extension().string();
  bool encoded = false;
  try {
    encoded = !ext.empty() && cv::imencode(ext, image, bytes);
  } catch (const cv::Exception&) {  // OpenCV has no encoder for the extension
    encoded = false;
  }
  if (!encoded) {
    return Status::Error(path + ": cannot encode an image for the extension '" + ext +
                         "' (expected .png, .jpg, .bmp, ...)");
  }
  return WriteOutput(path, std::string(bytes.begin(), bytes.end()), "image");
}

// The camera `kincal render` draws with: the intrinsics file's, else 640x480 at f = 820 px.
StatusOr<vision::CameraModel> RenderCamera(const std::string& intrinsics) {
  if (!intrinsics.empty()) return vision::ReadCameraYaml(intrinsics);
  return vision::CameraModel::Centred(640, 480, 820.0);
}

}  // namespace

Command AddTarget(CLI::App& app) {
  auto out = std::make_shared<std::string>();
  auto layout_file = std::make_shared<std::string>();
  app.add_option("--out", *out, "SVG file to write (print at 100 % scale)")->required();
  app.add_option("--layout", *layout_file, "target layout YAML (default: the thesis plate)");
  return [out, layout_file]() -> StatusOr<int> {
    KINCAL_ASSIGN_OR_RETURN(const auto layout, vision::ReadTargetLayoutYaml(*layout_file));
    const double x0 = -0.5 * layout.plate_size_m.x(), x1 = -x0;
    const double y0 = -0.5 * layout.plate_size_m.y(), y1 = -y0;
    const double pad = 0.0;
    const double w = (x1 - x0) * 1e3, h = (y1 - y0) * 1e3;
    std::ostringstream f;
    // Drawn seen from above: target x (forward) to the right, target y (left) up.
    f << std::setprecision(6) << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w
      << "mm' height='" << h << "mm' viewBox='0 0 " << w << " " << h << "'>\n<rect width='" << w
      << "' height='" << h << "' fill='white' stroke='black' stroke-width='0.2'/>\n";
    for (size_t i = 0; i < layout.markers.size(); ++i) {
      const auto& m = layout.markers[i];
      const double cx = (m.x() - x0 + pad) * 1e3, cy = (y1 - m.y() + pad) * 1e3;
      f << "<circle cx='" << cx << "' cy='" << cy << "' r='" << layout.marker_radius_m * 1e3
        << "' fill='black'/>\n"
        << "<text x='" << cx << "' y='" << cy + layout.marker_radius_m * 1e3 + 4
        << "' font-size='3' text-anchor='middle'>M" << i + 1 << "</text>\n";
    }
    const double ox = (0 - x0 + pad) * 1e3, oy = (y1 - 0 + pad) * 1e3;
    f << "<path d='M" << ox << " " << oy << " h12 M" << ox << " " << oy
      << " v-12' stroke='red' stroke-width='0.4'/>\n<text x='" << ox + 13 << "' y='" << oy + 1
      << "' font-size='3' fill='red'>x</text><text x='" << ox - 1 << "' y='" << oy - 13
      << "' font-size='3' fill='red'>y</text>\n<text x='2' y='" << h - 2
      << "' font-size='2.5'>kincal target '" << layout.name << "', markers "
      << layout.marker_radius_m * 2e3 << " mm, print at 100 %</text>\n</svg>\n";
    KINCAL_RETURN_IF_ERROR(WriteOutput(*out, f.str(), "target SVG"));
    std::cout << "wrote " << *out << " (" << w << " x " << h << " mm)\n";
    return 0;
  };
}

Command AddRender(CLI::App& app) {
  struct Args {
    std::string out, intrinsics, intrinsics_out, board, layout;
    double x = 0, y = 0, theta = 0, height = 1.5, target_height = 0.1, noise = 1.0, tilt = 0;
    uint64_t seed = 1;
  };
  auto a = std::make_shared<Args>();
  app.add_option("--out", a->out, "PNG to write")->required();
  app.add_option("--tilt", a->tilt,
                 "with --board: tilt of the board about its x axis, rad (calibration views)");
  app.add_option("--intrinsics", a->intrinsics, "camera YAML (default: 640x480, f = 820 px)");
  app.add_option("--x", a->x, "target x on the floor, m");
  app.add_option("--y", a->y, "target y on the floor, m");
  app.add_option("--theta", a->theta, "target heading, rad");
  app.add_option("--camera-height", a->height, "nadir camera height above the floor, m")
      ->capture_default_str();
  app.add_option("--noise", a->noise, "image noise, grey levels")
      ->check(AtLeastZero())
      ->capture_default_str();
  app.add_option("--seed", a->seed, "noise seed")->capture_default_str();
  app.add_option(
      "--board", a->board,
      "render a board lying on the floor instead: chessboard|circles|acircles:COLSxROWS:PITCH");
  app.add_option("--intrinsics-out", a->intrinsics_out, "also write the camera used as YAML");
  app.add_option("--layout", a->layout, "target layout YAML (default: the thesis plate)");
  return [a]() -> StatusOr<int> {
    const double below = a->board.empty() ? a->target_height : 0.0;  // what the camera sees
    if (!(a->height > below)) {
      return Status::Error("--camera-height: the camera must be above the " +
                           std::string(a->board.empty() ? "target" : "board") + " (" +
                           std::to_string(below) + " m above the floor)");
    }
    KINCAL_ASSIGN_OR_RETURN(const vision::CameraModel cam, RenderCamera(a->intrinsics));
    // Nadir camera: camera x = floor x, camera y = -floor y, camera z = -floor z.
    const Eigen::Matrix3d R_cf =
        Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Vector3d t_cf(0, 0, a->height);
    vision::Pose3 pose;
    pose.R = R_cf * Eigen::AngleAxisd(a->theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.t = R_cf * Eigen::Vector3d(a->x, a->y, a->target_height) + t_cf;
    std::mt19937_64 rng(a->seed);
    vision::RenderOptions ro;
    ro.noise_sigma = a->noise;
    KINCAL_ASSIGN_OR_RETURN(vision::TargetLayout layout, vision::ReadTargetLayoutYaml(a->layout));
    std::optional<Board> board;
    if (!a->board.empty()) {
      KINCAL_ASSIGN_OR_RETURN(board, Board::Parse(a->board));
      layout.name = a->board;
      layout.markers.clear();
      for (const auto& p : board->Points()) layout.markers.emplace_back(p.x(), p.y());
      layout.marker_radius_m = board->pitch / 4.0;
      pose.R = R_cf * Eigen::AngleAxisd(a->theta, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
               Eigen::AngleAxisd(a->tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
      pose.t = R_cf * Eigen::Vector3d(a->x, a->y, 0.0) + t_cf;  // on the floor (tilted about x)
    }
    if (!a->intrinsics_out.empty())
      KINCAL_RETURN_IF_ERROR(vision::WriteCameraYaml(cam, a->intrinsics_out));
    if (board && board->kind == "chessboard") {
      const auto fr =
          vision::RenderChessboard(cam, pose, board->cols, board->rows, board->pitch, ro, rng);
      KINCAL_RETURN_IF_ERROR(WriteImage(a->out, fr.image));
      return 0;
    }
    const auto fr = vision::RenderTarget(cam, pose, layout, ro, rng);
    KINCAL_RETURN_IF_ERROR(WriteImage(a->out, fr.image));
    std::cout << std::fixed << std::setprecision(4);
    for (size_t i = 0; i < fr.centres.size() && a->board.empty(); ++i) {
      std::cout << "M" << i + 1 << " true centre (" << fr.centres[i].x() << ", "
                << fr.centres[i].y() << ") px\n";
    }
    return 0;
  };
}

Command AddDetect(CLI::App& app) {
  struct Args {
    std::string image, overlay, intrinsics, layout;
    bool light_on_dark = false;
    int threshold = -1;
  };
  auto a = std::make_shared<Args>();
  app.add_option("image", a->image, "8-bit image")->required();
  app.add_option("--overlay", a->overlay, "PNG showing markers, ids, pose and rejected blobs");
  app.add_option("--intrinsics", a->intrinsics, "camera YAML: enables identification and pose");
  app.add_flag("--light-on-dark", a->light_on_dark, "markers brighter than the background");
  app.add_option("--threshold", a->threshold, "fixed threshold (default: Otsu)");
  app.add_option("--layout", a->layout, "target layout YAML (default: the thesis plate)");
  return [a]() -> StatusOr<int> {
    const cv::Mat grey = cv::imread(a->image, cv::IMREAD_GRAYSCALE);
    if (grey.empty()) return Status::Error(a->image + ": unreadable image");
    vision::DetectorOptions opt;
    opt.dark_on_light = !a->light_on_dark;
    opt.threshold = a->threshold;
    std::vector<vision::Rejected> rejected;
    auto markers = vision::DetectMarkers(grey, opt, {}, &rejected);
    cv::Mat vis;
    cv::cvtColor(grey, vis, cv::COLOR_GRAY2BGR);
    KINCAL_ASSIGN_OR_RETURN(const auto layout, vision::ReadTargetLayoutYaml(a->layout));
    std::string pose_text;
    if (!a->intrinsics.empty()) {
      KINCAL_ASSIGN_OR_RETURN(const auto cam, vision::ReadCameraYaml(a->intrinsics));
      if (cam.width != grey.cols || cam.height != grey.rows) {
        return Status::Error(a->image + ": image is " + std::to_string(grey.cols) + "x" +
                             std::to_string(grey.rows) + " but " + a->intrinsics + " is for " +
                             std::to_string(cam.width) + "x" + std::to_string(cam.height));
      }
      if (vision::IdentifyTarget(cam, layout, &markers)) {
        std::vector<Eigen::Vector3d> obj;
        std::vector<Eigen::Vector2d> norm;
        for (const auto& m : markers) {
          if (m.id < 0) continue;
          const auto& p = layout.markers[static_cast<size_t>(m.id)];
          obj.emplace_back(p.x(), p.y(), 0.0);
          norm.push_back(cam.PixelToNormalized(m.centre_px));
        }
        vision::Pose3 init;
        if (vision::PlanarInitialPose(obj, norm, &init)) {
          const auto r = vision::LowePose(obj, norm, init, cam.fx, 0.02);
          std::ostringstream s;
          s << std::setprecision(4) << "t = [" << r.pose.t.transpose() << "] m, rms " << r.rms_px
            << " px";
          pose_text = s.str();
        }
      }
    }
    for (const auto& m : markers) {
      const cv::Point2d c(m.centre_px.x(), m.centre_px.y());
      cv::circle(vis, c, static_cast<int>(std::lround(m.diameter_px / 2)), {0, 200, 0}, 1,
                 cv::LINE_AA);
      cv::drawMarker(vis, c, {0, 0, 255}, cv::MARKER_CROSS, 6);
      if (m.id >= 0)
        cv::putText(vis, "M" + std::to_string(m.id + 1), c + cv::Point2d(8, -8),
                    cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 200, 0});
      std::cout << std::fixed << std::setprecision(3) << "marker "
                << (m.id >= 0 ? "M" + std::to_string(m.id + 1) : "?") << " centre ("
                << m.centre_px.x() << ", " << m.centre_px.y() << ") px, diameter " << m.diameter_px
                << " px\n";
    }
    for (const auto& r : rejected) {
      cv::drawMarker(vis, cv::Point2d(r.centre_px.x(), r.centre_px.y()), {0, 140, 255},
                     cv::MARKER_TILTED_CROSS, 6);
      cv::putText(vis, r.reason, cv::Point2d(r.centre_px.x() + 6, r.centre_px.y() + 12),
                  cv::FONT_HERSHEY_SIMPLEX, 0.3, {0, 140, 255});
      std::cout << "rejected blob at (" << r.centre_px.x() << ", " << r.centre_px.y()
                << "): " << r.reason << "\n";
    }
    if (!pose_text.empty()) {
      cv::putText(vis, pose_text, {8, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {255, 80, 0});
      std::cout << "pose: " << pose_text << "\n";
    }
    if (!a->overlay.empty()) KINCAL_RETURN_IF_ERROR(WriteImage(a->overlay, vis));
    return markers.empty() ? 1 : 0;
  };
}

Command AddFloorcal(CLI::App& app) {
  struct Args {
    std::string image, board, intrinsics, out;
  };
  auto a = std::make_shared<Args>();
  app.add_option("--image", a->image, "image of a board lying on the floor")->required();
  app.add_option("--board", a->board, "KIND:COLSxROWS:PITCH (chessboard, circles, acircles)")
      ->required();
  app.add_option("--intrinsics", a->intrinsics, "camera YAML")->required();
  app.add_option("--out", a->out, "YAML with the floor extrinsics and their covariance")
      ->required();
  return [a]() -> StatusOr<int> {
    KINCAL_ASSIGN_OR_RETURN(const Board board, Board::Parse(a->board));
    const std::string& kind = board.kind;
    const int cols = board.cols, rows = board.rows;
    KINCAL_ASSIGN_OR_RETURN(const auto cam, vision::ReadCameraYaml(a->intrinsics));
    const cv::Mat img = cv::imread(a->image, cv::IMREAD_GRAYSCALE);
    if (img.empty()) return Status::Error(a->image + ": unreadable image");
    if (img.cols != cam.width || img.rows != cam.height)
      return Status::Error(a->image + ": size differs from the intrinsics' image size");
    std::vector<cv::Point2f> pts;
    bool found;
    if (kind == "chessboard") {
      found = cv::findChessboardCorners(img, {cols, rows}, pts);
      if (found)
        cv::cornerSubPix(img, pts, {5, 5}, {-1, -1},
                         {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4});
    } else {
      found = cv::findCirclesGrid(
          img, {cols, rows}, pts,
          kind == "circles" ? cv::CALIB_CB_SYMMETRIC_GRID : cv::CALIB_CB_ASYMMETRIC_GRID);
    }
    if (!found) return Status::Error(a->image + ": board " + a->board + " not found");
    const std::vector<Eigen::Vector3d> obj = board.Points();
    std::vector<Eigen::Vector2d> norm;
    for (const auto& p : pts) norm.push_back(cam.PixelToNormalized({p.x, p.y}));
    vision::Pose3 init;
    if (!vision::PlanarInitialPose(obj, norm, &init))
      return Status::Error(a->image + ": degenerate board view");
    auto r = vision::LowePose(obj, norm, init, cam.fx, 1.0);
    // Floor frame with z up, towards the camera: flip the board frame if its z points down.
    if ((-(r.pose.R.transpose() * r.pose.t)).z() < 0)
      r.pose.R = r.pose.R * Eigen::Vector3d(1, -1, -1).asDiagonal();
    // Scale the covariance by the observed reprojection error (sigma = rms).
    const double s2 = std::max(r.rms_px * r.rms_px, 1e-6);
    const Eigen::Matrix<double, 6, 6> cov = r.covariance * s2;
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    cv::Mat R(3, 3, CV_64F), t(3, 1, CV_64F), C(6, 6, CV_64F);
    for (int i = 0; i < 3; ++i) {
      t.at<double>(i) = r.pose.t[i];
      for (int j = 0; j < 3; ++j) R.at<double>(i, j) = r.pose.R(i, j);
    }
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) C.at<double>(i, j) = cov(i, j);
    fs << "R_cf" << R << "t_cf" << t << "covariance_t_rot" << C << "rms_px" << r.rms_px;
    KINCAL_RETURN_IF_ERROR(WriteOutput(a->out, fs.releaseAndGetString(), "floor extrinsics"));
    std::cout << std::fixed << std::setprecision(4)
              << "camera height above the floor plane: " << (-(r.pose.R.transpose() * r.pose.t)).z()
              << " m; t_cf = [" << r.pose.t.transpose() << "] m (1-sigma " << std::sqrt(cov(0, 0))
              << ", " << std::sqrt(cov(1, 1)) << ", " << std::sqrt(cov(2, 2)) << "); rms "
              << r.rms_px << " px\nwrote " << a->out << "\n";
    return 0;
  };
}

}  // namespace kincal::app
