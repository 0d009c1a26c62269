// A YAML file as kincal reads every one (a daemon config, a scenario, a target layout, a
// ROS camera_info): its text through ReadTextFile (any system's line endings, a byte-order
// mark, UTF-16; at most 16 MiB), parsed by yaml-cpp, and refused when a map holds a key
// twice. YAML says a map's keys are unique; yaml-cpp keeps both and answers with the first,
// so a setting added at the end of a file to override one above it was silently ignored.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <string_view>

#include "kincal/status.h"

namespace kincal {

// The file's root node (an empty file: a null node), or an error naming the file and the
// line: "run.yaml:32: key 'duration_s' is set twice (first on line 15)", "run.yaml:4: end of
// map not found". `what` names the file when it cannot be read ("cannot open scenario").
StatusOr<YAML::Node> LoadYamlFile(const std::string& path, std::string_view what);

}  // namespace kincal
