// The libcamera source without a camera (the VM test streams from a real pipeline).
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
#include "daemon/sources.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

// libcamera: the source starts the camera manager and, for a camera id that does not
// exist, says which cameras there are (none on a CI machine). Real capture needs a camera
// libcamera supports; vivid is not one (see docs/daemon.md).
TEST(Libcamera, AMissingCameraIsAClearError) {
  LibcameraOptions o;
  o.camera = "no-such-camera";
  auto src = MakeLibcameraSource(o);
  const Status started = src->Start();
  ASSERT_FALSE(started.ok()) << "started a camera that does not exist";
  const std::string& what = started.message();
  EXPECT_TRUE(what.find("libcamera: no cameras found") != std::string::npos ||
              what.find("libcamera: no camera 'no-such-camera' (found: ") != std::string::npos)
      << what;
}

}  // namespace
}  // namespace kincal::daemon
