// An exclusive lock on an output path for the life of the daemon: `PATH.lock` beside it,
// held with flock(2) and holding the holder's pid. A second kincald writing to the same
// recording or checkpoint is refused at start with the first one's pid, instead of both
// writing and one of them losing its output. Taking the lock also proves at start that the
// output's folder is writable. The lock file is left in place (removing it would race a
// third process); the kernel releases the lock when the descriptor closes, even on SIGKILL.
#pragma once

#include <string>

#include "kincal/status.h"

namespace kincal::daemon {

class PathLock {
 public:
  PathLock() = default;
  ~PathLock();
  PathLock(const PathLock&) = delete;
  PathLock& operator=(const PathLock&) = delete;

  // Locks `path` (for `what`: "recording", "checkpoint"). An error names the path and the
  // pid holding it, or the failed call with errno's text.
  Status Acquire(const std::string& path, const std::string& what);
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

}  // namespace kincal::daemon
