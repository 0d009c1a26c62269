// The preview: due by frame time at preview.rate_hz, downscaled by a whole factor (never
// enlarged), JPEG that decodes to the frame it came from (a disc where it was drawn),
// a busy worker skips and counts (live) or is waited for (lossless: the same previews
// every replay).
#include "daemon/preview.h"

#include <gtest/gtest.h>

#include <kincal/preview_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "daemon/daemon_test_util.h"
#include "kincal/vision/floor_view.h"

namespace kincal::daemon {
namespace {

struct PreviewHeard {
  std::vector<kincal::preview_t> frames;
  void On(const lcm::ReceiveBuffer*, const std::string&, const kincal::preview_t* m) {
    frames.push_back(*m);
  }
};

// A 1280x960 grey frame with a bright disc of radius 40 px at (cx, cy).
cv::Mat Scene(double cx, double cy) {
  cv::Mat m(960, 1280, CV_8UC1, cv::Scalar(40));
  cv::circle(m, cv::Point(static_cast<int>(cx), static_cast<int>(cy)), 40, cv::Scalar(220),
             cv::FILLED, cv::LINE_8);
  return m;
}

// LCM inside the process (memq), no recording.
bool OpenInProcess(Publisher* pub, bool lossless) {
  LcmOptions lcm;
  lcm.url = "memq://";
  return pub->Open(lcm, RecordOptions{}, 16, lossless).ok();
}

TEST(Preview, TheScaleIsTheSmallestWholeFactorThatFits) {
  EXPECT_EQ(PreviewStage::Scale(1280, 640), 2);
  EXPECT_EQ(PreviewStage::Scale(1280, 480), 3);  // 426 px
  EXPECT_EQ(PreviewStage::Scale(640, 480), 2);
  EXPECT_EQ(PreviewStage::Scale(640, 1024), 1);  // never enlarged
  EXPECT_EQ(PreviewStage::Scale(1920, 480), 4);
}

TEST(Preview, LosslessPublishesAtTheRateByFrameTimeAndDecodesToTheFrame) {
  Publisher pub;
  ASSERT_TRUE(OpenInProcess(&pub, /*lossless=*/true));
  PreviewHeard heard;
  pub.lcm()->subscribe("PREVIEW", &PreviewHeard::On, &heard);
  PreviewOptions o;
  o.rate_hz = 5;
  o.width = 640;
  int64_t offered = 0;
  {
    PreviewStage preview(o, "PREVIEW", &pub, /*lossless=*/true);
    const cv::Mat scene = Scene(700.0, 300.0);
    for (int i = 0; i < 60; ++i) {  // 2 s at 30 Hz
      preview.Offer(scene, 1'000'000 + i * 33'333, i);
      ++offered;
      while (pub.lcm()->handleTimeout(0) > 0) {
      }
    }
    preview.Drain();
    EXPECT_EQ(preview.published(), 10);
    EXPECT_EQ(preview.skipped(), 0);
  }
  while (pub.lcm()->handleTimeout(0) > 0) {
  }
  ASSERT_EQ(heard.frames.size(), 10u);
  EXPECT_EQ(heard.frames[0].frame_sequence, 0);
  EXPECT_EQ(heard.frames[1].utime - heard.frames[0].utime, 199'998);  // 6 frames later
  const kincal::preview_t& f = heard.frames.back();
  EXPECT_EQ(f.format, "jpeg");
  EXPECT_EQ(f.frame_sequence, 54);
  EXPECT_EQ(f.scale, 2);
  EXPECT_EQ(f.source_width, 1280);
  EXPECT_EQ(f.source_height, 960);
  EXPECT_EQ(f.width, 640);
  EXPECT_EQ(f.height, 480);
  EXPECT_EQ(f.size, static_cast<int32_t>(f.data.size()));
  const cv::Mat back = cv::imdecode(f.data, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(back.size(), cv::Size(640, 480));
  cv::Mat bright;
  cv::threshold(back, bright, 130, 255, cv::THRESH_BINARY);
  const cv::Moments m = cv::moments(bright, true);
  ASSERT_GT(m.m00, 0);
  // The disc where preview_t's mapping puts it: (u + 0.5) / scale - 0.5.
  EXPECT_NEAR(m.m10 / m.m00, 700.5 / 2 - 0.5, 0.5);
  EXPECT_NEAR(m.m01 / m.m00, 300.5 / 2 - 0.5, 0.5);
  EXPECT_NEAR(m.m00, M_PI * 20 * 20, 0.1 * M_PI * 20 * 20);
}

// 480 px on a 1280x960 camera: a factor of 3, the rightmost 2 columns cut, and the
// camera's pixels still where preview_t's mapping puts them.
TEST(Preview, AFactorOfThreeCutsTheEdgeAndKeepsTheMapping) {
  Publisher pub;
  ASSERT_TRUE(OpenInProcess(&pub, /*lossless=*/true));
  PreviewHeard heard;
  pub.lcm()->subscribe("PREVIEW", &PreviewHeard::On, &heard);
  {
    PreviewOptions o;
    o.width = 480;
    PreviewStage preview(o, "PREVIEW", &pub, /*lossless=*/true);
    preview.Offer(Scene(1000.0, 700.0), 1'000'000, 7);
    preview.Drain();
  }
  while (pub.lcm()->handleTimeout(0) > 0) {
  }
  ASSERT_EQ(heard.frames.size(), 1u);
  const kincal::preview_t& f = heard.frames[0];
  EXPECT_EQ(f.scale, 3);
  EXPECT_EQ(f.width, 426);
  EXPECT_EQ(f.height, 320);
  const cv::Mat back = cv::imdecode(f.data, cv::IMREAD_GRAYSCALE);
  cv::Mat bright;
  cv::threshold(back, bright, 130, 255, cv::THRESH_BINARY);
  const cv::Moments m = cv::moments(bright, true);
  ASSERT_GT(m.m00, 0);
  EXPECT_NEAR(m.m10 / m.m00, 1000.5 / 3 - 0.5, 0.5);
  EXPECT_NEAR(m.m01 / m.m00, 700.5 / 3 - 0.5, 0.5);
}

TEST(Preview, ATimeJumpBackRestartsTheSchedule) {
  Publisher pub;
  ASSERT_TRUE(OpenInProcess(&pub, /*lossless=*/true));
  PreviewOptions o;
  o.rate_hz = 5;
  PreviewStage preview(o, "PREVIEW", &pub, /*lossless=*/true);
  const cv::Mat scene = Scene(300.0, 300.0);
  for (int i = 0; i < 30; ++i) preview.Offer(scene, 100'000'000 + i * 33'333, i);     // 1 s
  for (int i = 0; i < 30; ++i) preview.Offer(scene, 1'000'000 + i * 33'333, 30 + i);  // back
  preview.Drain();
  EXPECT_EQ(preview.published(), 10);
}

// Live: the detection thread never waits; what the busy worker could not take is counted.
TEST(Preview, LiveNeverWaitsAndCountsWhatItSkips) {
  Publisher pub;
  ASSERT_TRUE(OpenInProcess(&pub, /*lossless=*/false));
  PreviewOptions o;
  o.rate_hz = 30;  // every frame due
  o.width = 1280;
  o.quality = 100;
  PreviewStage preview(o, "PREVIEW", &pub);
  const cv::Mat scene = Scene(300.0, 300.0);
  // One preview first, so that the worker is waiting for the next: the worker runs at
  // background priority, and on a loaded machine it could still be starting (holding its
  // lock) through the whole burst, which then skips every offer (a clean-clone run once
  // published none).
  preview.Offer(scene, 1'000'000, 0);
  preview.Drain();
  ASSERT_EQ(preview.published(), 1);
  for (int i = 1; i <= 200; ++i) preview.Offer(scene, 1'000'000 + i * 33'334, i);  // at once
  preview.Drain();
  EXPECT_EQ(preview.published() + preview.skipped(), 201);
  EXPECT_GT(preview.skipped(), 0) << "200 offers in a burst: the worker cannot keep up";
  EXPECT_GE(preview.published(), 2) << "the burst's first offer finds the worker waiting";
}

// The target's axes travel with the preview: projected from the pose offered with the
// frame (here by a stand-in projection: origin at (x, y) px, the ends 10 px along u and v),
// none for a frame without a pose.
TEST(Preview, ThePosesAxesTravelWithThePreview) {
  Publisher pub;
  ASSERT_TRUE(OpenInProcess(&pub, /*lossless=*/true));
  PreviewHeard heard;
  pub.lcm()->subscribe("PREVIEW", &PreviewHeard::On, &heard);
  PreviewOptions o;
  o.rate_hz = 5;
  {
    PreviewStage preview(o, "PREVIEW", &pub, /*lossless=*/true, {},
                         [](const Eigen::Vector3d& pose, std::array<Eigen::Vector2d, 3>* px) {
                           const Eigen::Vector2d at = pose.head<2>();
                           *px = {at, at + Eigen::Vector2d(10, 0), at + Eigen::Vector2d(0, 10)};
                           return pose.z() >= 0;  // "behind the camera" otherwise
                         });
    const cv::Mat scene = Scene(700.0, 300.0);
    const Eigen::Vector3d seen(640.0, 480.0, 0.0), behind(1.0, 1.0, -1.0);
    preview.Offer(scene, 1'000'000, 0, &seen);
    preview.Offer(scene, 1'200'000, 1);
    preview.Offer(scene, 1'400'000, 2, &behind);
    preview.Drain();
  }
  while (pub.lcm()->handleTimeout(0) > 0) {
  }
  ASSERT_EQ(heard.frames.size(), 3u);
  const kincal::preview_t& f = heard.frames[0];
  ASSERT_EQ(f.num_axes, 3);
  EXPECT_EQ(f.axes_u, (std::vector<double>{640.0, 650.0, 640.0}));
  EXPECT_EQ(f.axes_v, (std::vector<double>{480.0, 480.0, 490.0}));
  EXPECT_DOUBLE_EQ(f.axis_length_m, kPreviewAxisLengthM);
  EXPECT_EQ(heard.frames[1].num_axes, 0);
  EXPECT_TRUE(heard.frames[1].axes_u.empty());
  EXPECT_EQ(heard.frames[2].num_axes, 0);
}

// kincald's preview stage: none unless enabled; enabled, its previews carry the floor the
// default nadir camera sees and the axes of a pose projected through it.
TEST(Preview, KincaldsStageProjectsThroughItsCamera) {
  Publisher pub;
  ASSERT_TRUE(OpenInProcess(&pub, /*lossless=*/true));
  DaemonConfig c;
  const VisionSetup v = LoadVisionSetup(c).value();
  EXPECT_EQ(MakePreviewStage(c, v, &pub, true), nullptr);
  c.preview.enabled = true;
  c.lcm.preview_channel = "PREVIEW";
  PreviewHeard heard;
  pub.lcm()->subscribe("PREVIEW", &PreviewHeard::On, &heard);
  const Eigen::Vector3d pose(0.2, 0.1, 0.0);
  {
    const std::unique_ptr<PreviewStage> preview = MakePreviewStage(c, v, &pub, true);
    ASSERT_NE(preview, nullptr);
    preview->Offer(cv::Mat(v.camera.height, v.camera.width, CV_8UC1, cv::Scalar(90)), 1'000'000, 0,
                   &pose);
    preview->Drain();
  }
  while (pub.lcm()->handleTimeout(0) > 0) {
  }
  ASSERT_EQ(heard.frames.size(), 1u);
  const kincal::preview_t& f = heard.frames[0];
  EXPECT_EQ(f.num_floor, 32);
  ASSERT_EQ(f.num_axes, 3);
  std::array<Eigen::Vector2d, 3> px;
  ASSERT_TRUE(vision::TargetAxesInImage(v.camera, v.floor, v.target_height_m, pose,
                                        kPreviewAxisLengthM, &px));
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(f.axes_u[k], px[k].x());
    EXPECT_DOUBLE_EQ(f.axes_v[k], px[k].y());
  }
}

}  // namespace
}  // namespace kincal::daemon
