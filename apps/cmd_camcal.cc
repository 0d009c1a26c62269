// kincal camcal: camera calibration from board images or a points file, with
// cv::calibrateCamera on the same data side by side.
#include <array>
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

// The images in `dir`, sorted by name; an error names the folder.
StatusOr<std::vector<std::filesystem::path>> ImagesIn(const std::string& dir) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return Status::Error(dir + ": not a directory");
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const auto ext = it->path().extension().string();
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".pgm")
      files.push_back(it->path());
  }
  if (ec) return Status::Error(dir + ": cannot list the folder: " + ec.message());
  if (files.empty()) {
    return Status::Error(dir +
                         ": no images in the folder (expected .png, .jpg, .jpeg, .bmp or "
                         ".pgm files)");
  }
  std::sort(files.begin(), files.end());
  return files;
}

StatusOr<std::vector<vision::CalibrationView>> ViewsFromImages(const std::string& dir,
                                                               const Board& b, int* w, int* h) {
  KINCAL_ASSIGN_OR_RETURN(const auto files, ImagesIn(dir));
  std::vector<vision::CalibrationView> views;
  for (const auto& f : files) {
    const cv::Mat img = cv::imread(f.string(), cv::IMREAD_GRAYSCALE);
    if (img.empty()) {
      return Status::Error(f.string() + ": unreadable image, or larger than " +
                           std::to_string(kMaxImagePixels) + " pixels");
    }
    if (*w == 0) {
      *w = img.cols;
      *h = img.rows;
    } else if (img.cols != *w || img.rows != *h) {
      return Status::Error(f.string() + ": image size " + std::to_string(img.cols) + "x" +
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

// "WxH" (--image-size) into *w, *h; an error names the option.
Status ParseImageSize(const std::string& size, int* w, int* h) {
  static const std::regex re(R"((\d+)x(\d+))");
  std::smatch m;
  if (!std::regex_match(size, m, re))
    return Status::Error("--image-size '" + size + "': expected WxH, e.g. 640x480");
  auto dim = [&](const std::string& text, int* v) {
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *v);
    return ec == std::errc() && end == text.data() + text.size() && *v >= 1 &&
           *v <= vision::kMaxCameraSide;
  };
  if (!dim(m[1], w) || !dim(m[2], h)) {
    return Status::Error("--image-size '" + size + "': each side must be 1 to " +
                         std::to_string(vision::kMaxCameraSide) + " pixels");
  }
  return Status();
}

struct CamcalArgs {
  std::string images, board, points, size, out, json;
  bool k3 = false;
};

// The calibration's views, from the points file or the board images; the image size in *opt.
StatusOr<std::vector<vision::CalibrationView>> ReadViews(const CamcalArgs& a,
                                                         vision::CalibrationOptions* opt) {
  if (!a.points.empty() == !a.images.empty())
    return Status::Error("give either --images (with --board) or --points (with --image-size)");
  if (!a.points.empty()) {
    KINCAL_RETURN_IF_ERROR(ParseImageSize(a.size, &opt->width, &opt->height));
    return vision::ReadCalibrationPoints(a.points);
  }
  if (a.board.empty()) return Status::Error("--images needs --board KIND:COLSxROWS:PITCH");
  KINCAL_ASSIGN_OR_RETURN(const Board board, Board::Parse(a.board));
  return ViewsFromImages(a.images, board, &opt->width, &opt->height);
}

constexpr const char* kNames[9] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};

// A camera's intrinsics in kNames' order.
std::array<double, 9> Values(const vision::CameraModel& c) {
  return {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3};
}

// The calibration's values, 1-sigma and rms beside OpenCV's, as JSON.
nlohmann::json ToJson(const vision::CalibrationResult& r, const vision::OpenCvCalibration& cv,
                      const vision::CalibrationOptions& opt, size_t views, int np) {
  const auto ours = Values(r.camera), theirs = Values(cv.camera);
  nlohmann::json j, s, o;
  for (int i = 0; i < np; ++i) {
    j[kNames[i]] = ours[i];
    s[kNames[i]] = r.sigma[i];
    o[kNames[i]] = theirs[i];
  }
  j["sigma"] = s;
  j["rms_px"] = r.rms_px;
  j["image_width"] = opt.width;
  j["image_height"] = opt.height;
  j["views"] = views;
  o["rms_px"] = cv.rms_px;
  j["opencv"] = o;
  return j;
}

// The table of values, 1-sigma and OpenCV's on the same points.
void PrintTable(const vision::CalibrationResult& r, const vision::OpenCvCalibration& cv,
                size_t views, int np) {
  const auto ours = Values(r.camera), theirs = Values(cv.camera);
  std::cout << std::setprecision(6) << views << " views, " << r.points << " points\n"
            << std::setw(6) << "" << std::setw(16) << "kincal" << std::setw(14) << "1-sigma"
            << std::setw(16) << "cv::calibrate"
            << "\n";
  for (int i = 0; i < np; ++i) {
    std::cout << std::setw(6) << kNames[i] << std::setw(16) << ours[i] << std::setw(14)
              << r.sigma[i] << std::setw(16) << theirs[i] << "\n";
  }
  std::cout << std::setw(6) << "rms" << std::setw(16) << r.rms_px << std::setw(14) << ""
            << std::setw(16) << cv.rms_px << "  px\n";
}

StatusOr<int> RunCamcal(const CamcalArgs& a) {
  vision::CalibrationOptions opt;
  opt.use_k3 = a.k3;
  KINCAL_ASSIGN_OR_RETURN(const auto views, ReadViews(a, &opt));
  KINCAL_ASSIGN_OR_RETURN(const auto r, vision::CalibrateCamera(views, opt));
  KINCAL_RETURN_IF_ERROR(vision::WriteCameraYaml(r.camera, a.out));
  const std::string ros = CameraInfoPath(a.out);
  KINCAL_RETURN_IF_ERROR(vision::WriteCameraInfoYaml(r.camera, "kincal", ros));
  const auto cv_result = vision::CalibrateWithOpenCv(views, opt, r.camera);  // side by side
  const int np = a.k3 ? 9 : 8;
  PrintTable(r, cv_result, views.size(), np);
  std::cout << "wrote " << a.out << " and " << ros << " (ROS camera_info)\n";
  if (!a.json.empty()) {
    const nlohmann::json j = ToJson(r, cv_result, opt, views.size(), np);
    KINCAL_RETURN_IF_ERROR(WriteOutput(a.json, j.dump(2) + "\n", "calibration JSON"));
  }
  return 0;
}

}  // namespace

Command AddCamcal(CLI::App& app) {
  auto a = std::make_shared<CamcalArgs>();
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
  return [a]() -> StatusOr<int> { return RunCamcal(*a); };
}

}  // namespace kincal::app
