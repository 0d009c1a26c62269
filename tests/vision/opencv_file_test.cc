// OpenOpenCvFile (src/vision/opencv_file.cc): what OpenCV writes, and the same saved with a
// byte-order mark and CRLF, read alike; missing and garbage files and a folder named.
#include "vision/opencv_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "windows_text.h"

namespace kincal::vision {
namespace {

TEST(OpenCvFile, ByteOrderMarkAndCrlfAreTaken) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string plain = (dir / "kincal_ocv_lf.yaml").string();
  {
    cv::FileStorage out(plain, cv::FileStorage::WRITE);
    out << "answer" << 42 << "m" << cv::Mat::eye(2, 2, CV_64F);
  }
  std::ifstream in(plain);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> paths = {plain};
  for (const auto& [system, other] : ::kincal::testing::OtherSystemsText(text)) {
    paths.push_back((dir / ("kincal_ocv_" + std::to_string(paths.size()) + ".yaml")).string());
    std::ofstream(paths.back(), std::ios::binary) << other;
  }
  for (const std::string& path : paths) {
    cv::FileStorage fs;
    const Status s = OpenOpenCvFile(path, "test", &fs);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(static_cast<int>(fs["answer"]), 42) << path;
    cv::Mat m;
    fs["m"] >> m;
    EXPECT_EQ(m.at<double>(1, 1), 1.0) << path;
  }
}

TEST(OpenCvFile, MissingAndGarbageFilesAreNamed) {
  const auto dir = std::filesystem::temp_directory_path();
  cv::FileStorage fs;
  const std::string missing = (dir / "kincal_ocv_none.yaml").string();
  std::filesystem::remove(missing);
  const Status a = OpenOpenCvFile(missing, "camera", &fs);
  EXPECT_NE(a.message().find("kincal_ocv_none.yaml: cannot open camera: No such file"),
            std::string::npos)
      << a.message();
  const std::string garbage = (dir / "kincal_ocv_garbage.yaml").string();
  std::ofstream(garbage) << "%YAML:1.0\n---\n: : [\n";
  const Status b = OpenOpenCvFile(garbage, "camera", &fs);
  EXPECT_FALSE(b.ok());
  EXPECT_NE(b.message().find("kincal_ocv_garbage.yaml"), std::string::npos) << b.message();
  // A folder given for the file: named with errno's text, not OpenCV's assertion text.
  const Status c = OpenOpenCvFile(dir.string(), "camera", &fs);
  EXPECT_EQ(c.message(), dir.string() + ": cannot open camera: Is a directory");
}

}  // namespace
}  // namespace kincal::vision
