// Media device nodes: presence and lock holders.
#include "daemon/media_devices.h"

#include <fcntl.h>
#include <linux/media.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace kincal::daemon {
namespace {

std::string ProcessName(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/comm");
  std::string name;
  std::getline(in, name);
  return name.empty() ? "?" : name;
}

// The driver's name from MEDIA_IOC_DEVICE_INFO; empty when the node does not answer.
std::string DriverName(int fd) {
  media_device_info info{};
  if (::ioctl(fd, MEDIA_IOC_DEVICE_INFO, &info) != 0) return "";
  return std::string(info.driver, strnlen(info.driver, sizeof info.driver));
}

}  // namespace

std::vector<MediaNode> ListMediaNodes(const std::string& dev_dir) {
  std::vector<MediaNode> nodes;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dev_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("media", 0) != 0) continue;
    struct stat st {};
    if (::stat(e.path().c_str(), &st) != 0) continue;
    nodes.push_back({e.path().string(), st.st_rdev});
  }
  std::sort(nodes.begin(), nodes.end(),
            [](const MediaNode& a, const MediaNode& b) { return a.path < b.path; });
  return nodes;
}

bool AllPresent(const std::vector<MediaNode>& nodes) {
  for (const MediaNode& n : nodes) {
    struct stat st {};
    if (::stat(n.path.c_str(), &st) != 0 || st.st_rdev != n.rdev) return false;
  }
  return true;
}

std::string DescribeMediaHolders(const std::string& dev_dir) {
  std::string out;
  for (const MediaNode& n : ListMediaNodes(dev_dir)) {
    const int fd = ::open(n.path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    struct flock lk {};
    lk.l_type = F_WRLCK;
    lk.l_whence = SEEK_SET;
    if (::fcntl(fd, F_GETLK, &lk) == 0 && lk.l_type != F_UNLCK) {
      const std::string driver = DriverName(fd);
      out += (out.empty() ? "" : "; ") + n.path + (driver.empty() ? "" : " (" + driver + ")") +
             " is held by pid " + std::to_string(lk.l_pid) + " (" + ProcessName(lk.l_pid) + ")";
    }
    ::close(fd);
  }
  return out;
}

}  // namespace kincal::daemon
