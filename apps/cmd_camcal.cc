// kincal camcal: camera calibration from board images or a points file, with
// cv::calibrateCamera on the same data side by side.
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "board.h"
#include "commands.h"
#include "kincal/vision/calibration.h"
#include "kincal/vision/opencv_baseline.h"

namespace kincal::app {
namespace {

constexpr int kMaxImageSide = 65535;

std::vector<vision::CalibrationView> ViewsFromImages(const std::string& dir, const Board& b, int* w,
                                                     int* h) {
  std::vector<std::filesystem::path> files;
  if (!std::filesystem::is_directory(dir)) throw std::runtime_error(dir + ": not a directory");
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const auto ext = e.path().extension().string();
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".pgm")
      files.push_back(e.path());
  }
  if (files.empty()) {
    throw std::runtime_error(dir +
                             ": no images in the folder (expected .png, .jpg, .jpeg, .bmp or "
                             ".pgm files)");
  }
  std::sort(files.begin(), files.end());
  std::vector<vision::CalibrationView> views;
  for (const auto& f : files) {
    const cv::Mat img = cv::imread(f.string(), cv::IMREAD_GRAYSCALE);
    if (img.empty()) {
      throw std::runtime_error(f.string() + ": unreadable image, or larger than " +
                               std::to_string(kMaxImagePixels) + " pixels");
    }
    if (*w == 0) {
      *w = img.cols;
      *h = img.rows;
    } else if (img.cols != *w || img.rows != *h) {
      throw std::runtime_error(f.string() + ": image size " + std::to_string(img.cols) + "x" +
                               std::to_string(img.rows) + " differs from the first image's " +
                               std::to_string(*w) + "x" + std::to_string(*h));
    }
    std::vector<cv::Point2f> corners;
    const cv::Size size(b.cols, b.rows);
    bool found = false;
    if (b.kind == "chessboard") {
      found = cv::findChessboardCorners(
          img, size, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      if (found)
        cv::cornerSubPix(img, corners, {5, 5}, {-1, -1},
                         {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4});
    } else {
      found = cv::findCirclesGrid(
          img, size, corners,
          b.kind == "circles" ? cv::CALIB_CB_SYMMETRIC_GRID : cv::CALIB_CB_ASYMMETRIC_GRID);
    }
    if (!found) {
      std::cerr << "warning: " << f.string() << ": board not found, skipped\n";
      continue;
    }
    vision::CalibrationView v;
    v.name = f.filename().string();
    v.object = b.Points();
    for (const auto& c : corners) v.image.emplace_back(c.x, c.y);
    views.push_back(std::move(v));
  }
  return views;
}

// cam.yaml -> cam.camera_info.yaml, beside it.
std::string CameraInfoPath(const std::string& out) {
  std::filesystem::path p(out);
  p.replace_extension();
  return p.string() + ".camera_info.yaml";
}

// "WxH" (--image-size) into *w, *h; throws naming the option.
void ParseImageSize(const std::string& size, int* w, int* h) {
  static const std::regex re(R"((\d+)x(\d+))");
  std::smatch m;
  if (!std::regex_match(size, m, re))
    throw std::runtime_error("--image-size '" + size + "': expected WxH, e.g. 640x480");
  auto dim = [&](const std::string& text) {
    int v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || v < 1 || v > kMaxImageSide) {
      throw std::runtime_error("--image-size '" + size + "': each side must be 1 to " +
                               std::to_string(kMaxImageSide) + " pixels");
    }
    return v;
  };
  *w = dim(m[1]);
  *h = dim(m[2]);
}

}  // namespace

Command AddCamcal(CLI::App& app) {
  struct Args {
    std::string images, board, points, size, out, json;
    bool k3 = false;
  };
  auto a = std::make_shared<Args>();
  app.add_option("--images", a->images, "folder of board images");
  app.add_option("--board", a->board,
                 "KIND:COLSxROWS:PITCH (chessboard, circles, acircles; metres)");
  app.add_option("--points", a->points, "points file, header view,X,Y,Z,u,v");
  app.add_option("--image-size", a->size, "WxH (with --points)");
  app.add_option("--out", a->out,
                 "OpenCV FileStorage YAML to write; ROS camera_info YAML goes beside it "
                 "(NAME.camera_info.yaml)")
      ->required();
  app.add_option("--json", a->json, "JSON with values, 1-sigma and rms_px");
  app.add_flag("--k3", a->k3, "also estimate k3");
  return [a]() -> int {
    std::vector<vision::CalibrationView> views;
    vision::CalibrationOptions opt;
    opt.use_k3 = a->k3;
    if (!a->points.empty() == !a->images.empty())
      throw std::runtime_error(
          "give either --images (with --board) or --points (with --image-size)");
    if (!a->points.empty()) {
      ParseImageSize(a->size, &opt.width, &opt.height);
      views = OrThrow(vision::ReadCalibrationPoints(a->points));
    } else {
      if (a->board.empty()) throw std::runtime_error("--images needs --board KIND:COLSxROWS:PITCH");
      views = ViewsFromImages(a->images, Board::Parse(a->board), &opt.width, &opt.height);
    }
    const auto r = OrThrow(vision::CalibrateCamera(views, opt));
    if (const Status s = vision::WriteCameraYaml(r.camera, a->out); !s.ok())
      throw std::runtime_error(s.message());
    const std::string ros = CameraInfoPath(a->out);
    if (const Status s = vision::WriteCameraInfoYaml(r.camera, "kincal", ros); !s.ok())
      throw std::runtime_error(s.message());
    // OpenCV on the same points.
    const auto cv_result = vision::CalibrateWithOpenCv(views, opt, r.camera);
    const double cv_rms = cv_result.rms_px;
    const auto& c = cv_result.camera;
    const char* names[9] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};
    const double ours[9] = {r.camera.fx, r.camera.fy, r.camera.cx, r.camera.cy, r.camera.k1,
                            r.camera.k2, r.camera.p1, r.camera.p2, r.camera.k3};
    const double theirs[9] = {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3};
    const int np = a->k3 ? 9 : 8;
    std::cout << std::setprecision(6) << views.size() << " views, " << r.points << " points\n"
              << std::setw(6) << "" << std::setw(16) << "kincal" << std::setw(14) << "1-sigma"
              << std::setw(16) << "cv::calibrate"
              << "\n";
    for (int i = 0; i < np; ++i) {
      std::cout << std::setw(6) << names[i] << std::setw(16) << ours[i] << std::setw(14)
                << r.sigma[i] << std::setw(16) << theirs[i] << "\n";
    }
    std::cout << std::setw(6) << "rms" << std::setw(16) << r.rms_px << std::setw(14) << ""
              << std::setw(16) << cv_rms << "  px\n";
    std::cout << "wrote " << a->out << " and " << ros << " (ROS camera_info)\n";
    if (!a->json.empty()) {
      nlohmann::json j, s, o;
      for (int i = 0; i < np; ++i) {
        j[names[i]] = ours[i];
        s[names[i]] = r.sigma[i];
        o[names[i]] = theirs[i];
      }
      j["sigma"] = s;
      j["rms_px"] = r.rms_px;
      j["image_width"] = opt.width;
      j["image_height"] = opt.height;
      j["views"] = views.size();
      o["rms_px"] = cv_rms;
      j["opencv"] = o;
      WriteOutput(a->json, j.dump(2) + "\n", "calibration JSON");
    }
    return 0;
  };
}

}  // namespace kincal::app
