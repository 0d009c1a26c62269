// Media device nodes: which exist, and who holds them. A regular file stands in for
// /dev/media0 (a lock on it is the same lockf(3) lock libcamera takes on the device).
#include "daemon/media_devices.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "daemon/daemon_test_util.h"

namespace kincal::daemon {
namespace {

TEST(MediaDevices, ListsNodesAndTellsWhenOneVanishes) {
  const std::string dir = test_util::TempPath("dev_a");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/media0") << "";
  std::ofstream(dir + "/video0") << "";
  const std::vector<MediaNode> nodes = ListMediaNodes(dir);
  ASSERT_EQ(nodes.size(), 1u);
  EXPECT_EQ(nodes[0].path, dir + "/media0");
  EXPECT_TRUE(AllPresent(nodes));
  std::filesystem::remove(dir + "/media0");
  EXPECT_FALSE(AllPresent(nodes));
  EXPECT_TRUE(ListMediaNodes(dir + "/missing").empty());
}

TEST(MediaDevices, NamesTheProcessHoldingANode) {
  const std::string dir = test_util::TempPath("dev_b");
  std::filesystem::create_directories(dir);
  const std::string node = dir + "/media0";
  std::ofstream(node) << "x";
  EXPECT_EQ(DescribeMediaHolders(dir), "") << "nobody holds it";
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  if (child == 0) {  // holds the lock until killed
    const int fd = ::open(node.c_str(), O_RDWR);
    const bool locked = fd >= 0 && lockf(fd, F_TLOCK, 0) == 0;
    const char c = locked ? '1' : '0';
    if (write(ready[1], &c, 1) != 1) _exit(1);
    pause();
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  ASSERT_EQ(c, '1');
  const std::string held = DescribeMediaHolders(dir);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  close(ready[0]);
  close(ready[1]);
  EXPECT_NE(held.find(node + " is held by pid " + std::to_string(child) + " ("), std::string::npos)
      << held;
}

}  // namespace
}  // namespace kincal::daemon
