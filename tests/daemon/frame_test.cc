// Frames: every pixel format decodes to the same grey; bad buffers are errors, not crashes.
#include "kincal/daemon/frame.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <thread>

#include "daemon/daemon_test_util.h"
#include "source_dir.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

cv::Mat TestImage() {
  cv::Mat g(48, 64, CV_8UC1);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c)
      g.at<uint8_t>(r, c) = static_cast<uint8_t>((r * 7 + c * 3) % 251);
  return g;
}

TEST(Frames, EveryFormatDecodesToTheSameGrey) {
  const cv::Mat g = TestImage();
  cv::Mat out;
  Frame f;
  FromGrey(g, &f);
  ASSERT_TRUE(ToGrey(f, &out).ok());
  EXPECT_EQ(cv::norm(out, g, cv::NORM_INF), 0.0);
  // YUYV: Y carries the grey level.
  Frame y;
  y.width = g.cols;
  y.height = g.rows;
  y.stride = 2 * g.cols + 16;  // padded rows
  y.format = PixelFormat::kYuyv;
  y.data.assign(static_cast<size_t>(y.stride) * g.rows, 128);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c)
      y.data[static_cast<size_t>(r) * y.stride + 2 * c] = g.at<uint8_t>(r, c);
  ASSERT_TRUE(ToGrey(y, &out).ok());
  EXPECT_EQ(cv::norm(out, g, cv::NORM_INF), 0.0);
  // PNG (lossless) and MJPEG (lossy: small error).
  for (const auto& [ext, fmt, tol] : {std::tuple{".png", PixelFormat::kPng, 0.0},
                                      std::tuple{".jpg", PixelFormat::kMjpeg, 12.0}}) {
    Frame e;
    e.width = g.cols;
    e.height = g.rows;
    e.format = fmt;
    cv::imencode(ext, g, e.data);
    ASSERT_TRUE(ToGrey(e, &out).ok());
    EXPECT_LE(cv::norm(out, g, cv::NORM_INF), tol) << ext;
  }
  // Packed colour.
  Frame b;
  b.width = g.cols;
  b.height = g.rows;
  b.stride = 3 * g.cols;
  b.format = PixelFormat::kBgr24;
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c)
      for (int k = 0; k < 3; ++k) b.data.push_back(g.at<uint8_t>(r, c));
  ASSERT_TRUE(ToGrey(b, &out).ok());
  EXPECT_LE(cv::norm(out, g, cv::NORM_INF), 1.0);
}

TEST(Frames, BadBuffersAreErrorsNotCrashes) {
  const cv::Mat g = TestImage();
  Frame f;
  FromGrey(g, &f);
  cv::Mat out;
  f.data.resize(f.data.size() - 1);  // one byte short
  EXPECT_FALSE(ToGrey(f, &out).ok());
  f.width = -3;
  EXPECT_FALSE(ToGrey(f, &out).ok());
  Frame j;
  j.width = 64;
  j.height = 48;
  j.format = PixelFormat::kMjpeg;
  j.data = {0xff, 0xd8, 0xff, 0x00, 0x12, 0x34};  // a JPEG header and nothing else
  EXPECT_FALSE(ToGrey(j, &out).ok());
  Frame p;
  p.width = 32;  // encoded image is 64x48: the size is checked
  p.height = 48;
  p.format = PixelFormat::kPng;
  cv::imencode(".png", g, p.data);
  const Status refused = ToGrey(p, &out);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("declares 64x48, expected 32x48"), std::string::npos)
      << refused.message();
  // Content in another format is not handed to whichever OpenCV decoder claims it (the
  // fuzzer found a DICOM reader that aborts the process): the declared format only.
  p.width = 64;
  cv::Mat ok;
  ASSERT_TRUE(ToGrey(p, &ok).ok());
  EXPECT_EQ(cv::norm(ok, g, cv::NORM_INF), 0.0);
  Frame other = p;
  other.format = PixelFormat::kMjpeg;  // PNG bytes labelled MJPG
  EXPECT_FALSE(ToGrey(other, &out).ok());
  std::ifstream crash(::kincal::testing::SourceDir() + "/fuzz/corpus/frame/regress-dicom-abort",
                      std::ios::binary);
  ASSERT_TRUE(crash.good());
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(crash)), {});
  ASSERT_GT(bytes.size(), 5u);
  other.width = bytes[1] + 1;  // as the harness builds its frame: format, width, height, stride
  other.height = bytes[2] + 1;
  other.data.assign(bytes.begin() + 5, bytes.end());
  for (PixelFormat fmt : {PixelFormat::kMjpeg, PixelFormat::kPng}) {
    other.format = fmt;
    EXPECT_FALSE(ToGrey(other, &out).ok());
  }
}

TEST(Frames, PixelFormatsAreParsedAndAnUnknownOneIsNamed) {
  for (PixelFormat f : {PixelFormat::kGrey, PixelFormat::kYuyv, PixelFormat::kMjpeg,
                        PixelFormat::kPng, PixelFormat::kBgr24, PixelFormat::kRgb24}) {
    const StatusOr<PixelFormat> back = ParsePixelFormat(PixelFormatName(f));
    ASSERT_TRUE(back.ok()) << PixelFormatName(f);
    EXPECT_EQ(back.value(), f);
  }
  const StatusOr<PixelFormat> nv12 = ParsePixelFormat("NV12\r");
  ASSERT_FALSE(nv12.ok());
  EXPECT_EQ(nv12.status().message(),
            "pixel format 'NV12\\r': expected GREY, YUYV, MJPG, PNG, BGR3 or RGB3");
}

}  // namespace
}  // namespace kincal::daemon
