#include "daemon/path_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace kincal::daemon {

PathLock::~PathLock() {
  if (fd_ >= 0) ::close(fd_);
}

Status PathLock::Acquire(const std::string& path, const std::string& what) {
  // A folder where the output goes could never be replaced by it: said now, not when the
  // first checkpoint or the recording is written.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    return Status::Error(path + ": the " + what + " would replace a folder: name a file");
  }
  const std::string lock = path + ".lock";
  const int fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    return Status::Error(path + ": cannot lock the " + what + " (" + lock +
                         "): " + std::strerror(errno));
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[32] = {};
    const ssize_t n = ::pread(fd, buf, sizeof(buf) - 1, 0);
    ::close(fd);
    if (err == EWOULDBLOCK) {
      const std::string pid = n > 0 ? std::string(buf, static_cast<size_t>(n)) : "unknown";
      return Status::Error(path + ": the " + what + " is in use by another process (pid " +
                           pid.substr(0, pid.find('\n')) + ", lock " + lock + ")");
    }
    return Status::Error(path + ": cannot lock the " + what + " (" + lock +
                         "): " + std::strerror(err));
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
    const int err = errno;
    ::close(fd);
    return Status::Error(lock + ": cannot write the lock holder's pid: " + std::strerror(err));
  }
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
  return {};
}

}  // namespace kincal::daemon
