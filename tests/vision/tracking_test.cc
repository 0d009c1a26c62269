// MarkerTracker (src/vision/tracking.cc): searches near the last target and falls back to
// the whole frame when the target jumps.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <random>

#include "kincal/vision/calibration.h"
#include "kincal/vision/camera.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/synthetic.h"
#include "kincal/vision/target.h"
#include "vision/vision_test_util.h"

namespace kincal::vision {
namespace {

using namespace test_util;

TEST(Tracking, TrackerSearchesNearTheLastTargetAndFallsBack) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  std::mt19937_64 rng(9);
  MarkerTracker tracker(cam, layout, DetectorOptions{});
  const FloorExtrinsics floor = Overhead();
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector3d q =
        k < 9 ? Eigen::Vector3d(0.01 * k, 0.0, 0.05 * k) : Eigen::Vector3d(-0.2, 0.2, 1.0);
    const RenderedFrame fr =
        RenderTarget(cam, TargetPose(floor, q, 0.1), layout, RenderOptions{}, rng);
    const auto markers = tracker.Track(fr.image);
    ASSERT_EQ(markers.size(), 4u) << k;
    for (const auto& m : markers)
      EXPECT_LT((m.centre_px - fr.centres[static_cast<size_t>(m.id)]).norm(), 0.1);
    if (k > 0 && k < 9) {
      EXPECT_FALSE(tracker.last_was_full_frame()) << k;
    }
  }
  EXPECT_EQ(tracker.full_frame_searches(), 2);  // the first frame and the jump
}

}  // namespace
}  // namespace kincal::vision
