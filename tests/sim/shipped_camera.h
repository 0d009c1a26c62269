// Shared by tests that render through the camera kincald's simulator uses by default:
// 640x480, f 500 px, 2 m above the floor looking straight down, the large plate 0.1 m
// above the floor (config/kincald_sim.yaml).
#pragma once

#include <string>

#include "kincal/sim/thesis_vision.h"
#include "kincal/vision/setup_files.h"
#include "source_dir.h"

namespace kincal::test_util {

inline ThesisVision ShippedCamera() {
  ThesisVision v;
  v.camera = vision::CameraModel::Centred(640, 480, 500.0);
  v.floor = vision::NadirFloor(2.0);
  v.layout =
      vision::ReadTargetLayoutYaml(::kincal::testing::SourceDir() + "/config/target_large.yaml")
          .value();
  v.target_height_m = 0.1;
  return v;
}

}  // namespace kincal::test_util
