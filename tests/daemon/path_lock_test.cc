// PathLock: one holder per output path; the second is told the first one's pid; the lock
// goes with the holder; an unwritable folder is an error at once, with errno's text.
#include "daemon/path_lock.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include "daemon/daemon_test_util.h"

namespace kincal::daemon {
namespace {

using test_util::TempPath;

TEST(PathLock, ASecondHolderIsRefusedWithTheFirstOnesPid) {
  const std::string path = TempPath("locked.lcm");
  PathLock first;
  ASSERT_TRUE(first.Acquire(path, "recording").ok());
  // flock locks belong to the open file description: another process sees the conflict.
  const pid_t child = ::fork();
  if (child == 0) {
    PathLock second;
    const Status s = second.Acquire(path, "recording");
    const bool named =
        !s.ok() && s.message().find("the recording is in use by another process (pid " +
                                    std::to_string(::getppid())) != std::string::npos;
    ::_exit(named ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

TEST(PathLock, TheLockGoesWithItsHolder) {
  const std::string path = TempPath("released.json");
  {
    PathLock first;
    ASSERT_TRUE(first.Acquire(path, "checkpoint").ok());
  }
  const pid_t child = ::fork();
  if (child == 0) {
    PathLock second;
    ::_exit(second.Acquire(path, "checkpoint").ok() ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

TEST(PathLock, AFolderThatIsNotThereIsAnErrorWithErrno) {
  PathLock lock;
  const Status s = lock.Acquire(TempPath("no_such_folder") + "/ck.json", "checkpoint");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cannot lock the checkpoint"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("No such file or directory"), std::string::npos) << s.message();
  EXPECT_FALSE(lock.held());
}

}  // namespace
}  // namespace kincal::daemon
