// The detection stage on rendered frames (no camera, no threads but its own loop): a frame
// with the target gives a valid pose near the truth, published on the pose channel (and
// the markers when asked) and handed to the filter's queue; a frame without it gives an
// invalid pose and the time without a target grows; an undecodable frame is counted and
// its error shown; the pose queue is closed when the frames end.
#include "daemon/detection_stage.h"

#include <gtest/gtest.h>

#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <random>

#include "daemon/daemon_test_util.h"
#include "kincal/vision/target.h"

namespace kincal::daemon {
namespace {

struct Heard {
  std::map<std::string, int> count;
  double last_x = 0;
  void On(const lcm::ReceiveBuffer* b, const std::string& channel) {
    ++count[channel];
    kincal::pose_t m;
    if (channel == "POSE" && m.decode(b->data, 0, b->data_size) > 0) last_x = m.x;
  }
};

TEST(DetectionStage, FramesBecomePublishedPosesInOrder) {
  const DaemonConfig c = test_util::SimConfig(1);
  const VisionSetup vis = LoadVisionSetup(c).value();
  PoseStage poses(c.pose, c.detector, vis);
  Publisher pub;
  LcmOptions lcm;
  lcm.url = "memq://";
  ASSERT_TRUE(pub.Open(lcm, RecordOptions{}, 16, false).ok());
  Heard heard;
  pub.lcm()->subscribe(".*", &Heard::On, &heard);
  BoundedQueue<Frame> in(16, FullPolicy::kBlock);
  BoundedQueue<PoseSample> out(16, FullPolicy::kBlock);
  CounterSet counters;
  DetectionStage stage(&poses, {"POSE", "MARKERS", true, 0.05}, &pub, &in, &out, &counters);

  // Three frames: the target at a known pose, an empty floor, and a frame too short to be
  // an image.
  const Eigen::Vector3d truth(0.12, -0.07, 0.4);
  const vision::Pose3 pose = vision::CameraPoseOnFloor(vis.floor, truth, vis.target_height_m);
  std::mt19937_64 rng(4);
  vision::RenderOptions ro;
  Frame with, without, broken;
  FromGrey(vision::RenderTarget(vis.camera, pose, vis.layout, ro, rng).image, &with);
  FromGrey(cv::Mat(vis.camera.height, vis.camera.width, CV_8UC1, cv::Scalar(128)), &without);
  broken = with;
  broken.data.resize(10);
  with.utime = 1'000'000;
  with.sequence = 0;
  without.utime = 1'500'000;
  without.sequence = 1;
  broken.utime = 1'600'000;
  broken.sequence = 2;
  in.Push(with);
  in.Push(without);
  in.Push(broken);
  in.Close();
  stage.Run();

  PoseSample p;
  ASSERT_TRUE(out.TryPop(p));
  EXPECT_TRUE(p.valid);
  EXPECT_EQ(p.sequence, 0);
  EXPECT_LT((p.xytheta.head<2>() - truth.head<2>()).norm(), 0.005);
  ASSERT_TRUE(out.TryPop(p));
  EXPECT_FALSE(p.valid);
  EXPECT_EQ(p.sequence, 1);
  EXPECT_FALSE(out.TryPop(p)) << "the broken frame gives no pose";
  EXPECT_TRUE(out.closed_and_empty());

  EXPECT_EQ(counters.poses_valid.load(), 1);
  EXPECT_EQ(counters.poses_invalid.load(), 1);
  EXPECT_EQ(counters.frames_bad.load(), 1);
  EXPECT_EQ(counters.poses_published.load(), 2);
  while (pub.lcm()->handleTimeout(0) > 0) {
  }
  EXPECT_EQ(heard.count["POSE"], 2);
  EXPECT_EQ(heard.count["MARKERS"], 2);
  const DetectionStage::Status s = stage.TakeStatus(true);
  EXPECT_FALSE(s.last_frame_error.empty());
  EXPECT_NEAR(s.seconds_without_target, 0.5, 1e-9);  // the empty frame came 0.5 s later
}

}  // namespace
}  // namespace kincal::daemon
