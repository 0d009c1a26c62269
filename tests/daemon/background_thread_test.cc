// A background worker's thread runs kBackgroundNice below the thread that started it, and
// only that thread is lowered.
#include "daemon/background_thread.h"

#include <gtest/gtest.h>

#include <thread>

namespace kincal::daemon {
namespace {

int ThisThreadsNice() {
  return getpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)));
}

TEST(BackgroundThread, LowersOnlyTheCallingThread) {
  const int before = ThisThreadsNice();
  int inside = 0;
  std::thread t([&inside] {
    RunThisThreadInTheBackground();
    inside = ThisThreadsNice();
  });
  t.join();
  EXPECT_EQ(inside, std::min(before + kBackgroundNice, 19));
  EXPECT_EQ(ThisThreadsNice(), before);
}

}  // namespace
}  // namespace kincal::daemon
