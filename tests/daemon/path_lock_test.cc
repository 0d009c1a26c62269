// PathLock: one holder per output path; the second is told the first one's pid; the lock
// goes with the holder; an unwritable folder, or a folder where the file should be, is an
// error at once.
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

// checkpoint.path: / ran to the end and failed at the first checkpoint, 10 s in.
TEST(PathLock, AFolderWhereTheFileShouldBeIsRefusedAtOnce) {
  PathLock lock;
  const std::string folder = TempPath("a_folder");
  std::filesystem::create_directories(folder);
  const Status s = lock.Acquire(folder, "checkpoint");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), folder + ": the checkpoint would replace a folder: name a file");
  EXPECT_FALSE(lock.held());
  EXPECT_FALSE(std::filesystem::exists(folder + ".lock"));
}

}  // namespace
}  // namespace kincal::daemon
