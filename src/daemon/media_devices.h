// Media-controller device nodes (/dev/mediaN) as libcamera uses them: which exist (to tell
// a camera whose device vanished from one that stalled), and which another process holds
// (libcamera locks a media device with lockf(3) while it uses the camera).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace kincal::daemon {

struct MediaNode {
  std::string path;
  dev_t rdev = 0;
};

// The media nodes in `dev_dir` ("mediaN" entries).
std::vector<MediaNode> ListMediaNodes(const std::string& dev_dir = "/dev");

// True when every node still exists as the same device.
bool AllPresent(const std::vector<MediaNode>& nodes);

// "/dev/media0 (vimc) is held by pid 123 (kincald)" for each node another process has
// locked, joined by "; "; empty when none is.
std::string DescribeMediaHolders(const std::string& dev_dir = "/dev");

}  // namespace kincal::daemon
