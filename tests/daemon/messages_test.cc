#include "daemon/messages.h"

#include <gtest/gtest.h>

#include <kincal/calibration_t.hpp>
#include <kincal/frame_t.hpp>
#include <kincal/health_t.hpp>
#include <kincal/markers_t.hpp>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <opencv2/imgcodecs.hpp>

#include "lcm_round_trip.h"

namespace kincal::daemon {
namespace {

using testing::RoundTrip;

TEST(Messages, PoseCovarianceIsRowMajorAndMarkersKeepTheirCount) {
  PoseSample p;
  p.utime = 10;
  p.device_utime = 7;
  p.valid = true;
  p.xytheta = {1.5, -0.25, 0.3};
  p.covariance << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  p.num_markers = 3;
  for (int i = 0; i < 3; ++i) {
    p.u[static_cast<size_t>(i)] = 100.0 + i;
    p.v[static_cast<size_t>(i)] = 50.0 - i;
    p.id[static_cast<size_t>(i)] = i == 2 ? -1 : i;
  }
  kincal::pose_t pm;
  FillPoseMessage(p, &pm);
  const auto pr = RoundTrip(pm);
  EXPECT_DOUBLE_EQ(pr.x, 1.5);
  EXPECT_DOUBLE_EQ(pr.theta, 0.3);
  EXPECT_DOUBLE_EQ(pr.covariance[1], 2);  // (0, 1)
  EXPECT_DOUBLE_EQ(pr.covariance[3], 4);  // (1, 0)
  EXPECT_EQ(pr.source_utime, 7);
  EXPECT_EQ(pr.valid, 1);
  kincal::markers_t mm;
  FillMarkersMessage(p, 0.05, &mm);
  const auto mr = RoundTrip(mm);
  ASSERT_EQ(mr.num_markers, 3);
  EXPECT_DOUBLE_EQ(mr.u[2], 102.0);
  EXPECT_DOUBLE_EQ(mr.v[1], 49.0);
  EXPECT_EQ(mr.id[2], -1);
  EXPECT_DOUBLE_EQ(mr.sigma_px[0], 0.05);
}

TEST(Messages, PngFramesDecodeToTheSamePixels) {
  Frame f;
  f.width = 40;
  f.height = 30;
  f.stride = 40;
  f.format = PixelFormat::kGrey;
  f.data.resize(40 * 30);
  for (size_t i = 0; i < f.data.size(); ++i) f.data[i] = static_cast<uint8_t>((i * 37) % 251);
  std::vector<uint8_t> png;
  kincal::frame_t m;
  ASSERT_TRUE(FillFrameMessage(f, FrameEncoding::kPng, &png, &m).ok());
  EXPECT_EQ(m.pixel_format, "PNG");
  EXPECT_LT(m.size, 40 * 30 + 200);
  const cv::Mat decoded = cv::imdecode(m.data, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(decoded.cols, 40);
  ASSERT_EQ(decoded.rows, 30);
  EXPECT_EQ(std::vector<uint8_t>(decoded.datastart, decoded.dataend), f.data);
  ASSERT_TRUE(FillFrameMessage(f, FrameEncoding::kRaw, &png, &m).ok());
  EXPECT_EQ(m.pixel_format, "GREY");
  EXPECT_EQ(m.data, f.data);
}

// frame_encoding: jpeg records grey frames as JPEG (replayed as MJPG): smooth images come
// back within a grey level or two, and decode through the MJPG path to the same size.
TEST(Messages, JpegFramesReplayAsMjpgCloseToThePixels) {
  Frame f;
  f.width = 64;
  f.height = 48;
  f.stride = 64;
  f.format = PixelFormat::kGrey;
  f.data.resize(64 * 48);
  for (int r = 0; r < 48; ++r) {
    for (int c = 0; c < 64; ++c)
      f.data[static_cast<size_t>(r * 64 + c)] = static_cast<uint8_t>(60 + 2 * c + r);
  }
  std::vector<uint8_t> buf;
  kincal::frame_t m;
  ASSERT_TRUE(FillFrameMessage(f, FrameEncoding::kJpeg, &buf, &m).ok());
  EXPECT_EQ(m.pixel_format, "MJPG");
  EXPECT_LT(m.size, 64 * 48);
  Frame back;
  back.width = 64;
  back.height = 48;
  back.stride = 64;
  back.format = PixelFormat::kMjpeg;
  back.data.assign(m.data.begin(), m.data.end());
  cv::Mat grey;
  ASSERT_TRUE(ToGrey(back, &grey).ok());
  ASSERT_EQ(grey.cols, 64);
  int worst = 0;
  for (int r = 0; r < 48; ++r) {
    for (int c = 0; c < 64; ++c)
      worst = std::max(worst,
                       std::abs(grey.at<uint8_t>(r, c) - f.data[static_cast<size_t>(r * 64 + c)]));
  }
  EXPECT_LE(worst, 3);
}

// A grey frame too short for its size cannot be PNG-encoded: it is recorded raw, as it
// came, and the error says why (it used to stop the capture thread).
TEST(Messages, AFrameThatCannotBeEncodedIsRecordedRaw) {
  Frame f;
  f.width = 64;
  f.height = 48;
  f.stride = 64;
  f.format = PixelFormat::kGrey;
  f.data.assign(10, 7);
  std::vector<uint8_t> png;
  kincal::frame_t m;
  const Status s = FillFrameMessage(f, FrameEncoding::kPng, &png, &m);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("GREY"), std::string::npos) << s.message();
  EXPECT_EQ(m.pixel_format, "GREY");
  EXPECT_EQ(m.size, 10);
  EXPECT_EQ(m.data, f.data);
}

TEST(Messages, HealthCarriesEveryCounter) {
  DaemonCounters c;
  int64_t k = 1;
#define KINCAL_SET(name, meaning) c.name = 1000 + k++;
  KINCAL_DAEMON_COUNTERS(KINCAL_SET)
#undef KINCAL_SET
  kincal::health_t h{};
  FillHealthCounters(c, &h);
  const auto r = RoundTrip(h);
#define KINCAL_EXPECT(name, meaning) EXPECT_EQ(r.name, c.name) << #name;
  KINCAL_DAEMON_COUNTERS(KINCAL_EXPECT)
#undef KINCAL_EXPECT
}

}  // namespace
}  // namespace kincal::daemon
