// Reading the vision set-up from files: target layouts (YAML) and floor extrinsics
// (OpenCV FileStorage YAML written by `kincal floorcal`). Errors name the file and line.
#pragma once

#include <string>

#include "kincal/status.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/target.h"

namespace kincal::vision {

// config/target_*.yaml: name, plate_size_m [w, h], marker_radius_m, dark_on_light,
// markers [[x, y], ...] (m). An empty path gives the thesis plate.
StatusOr<TargetLayout> ReadTargetLayoutYaml(const std::string& path);

// R_cf and t_cf as written by `kincal floorcal`.
StatusOr<FloorExtrinsics> ReadFloorYaml(const std::string& path);

// A camera looking straight down from `height_m` above the floor origin: image x along
// floor x, image y along floor -y.
FloorExtrinsics NadirFloor(double height_m);

}  // namespace kincal::vision
