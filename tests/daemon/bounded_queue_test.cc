// BoundedQueue: each full-queue policy keeps what it says and counts what it drops; items move
// by swap.
#include "daemon/bounded_queue.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <thread>

#include "daemon/daemon_test_util.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

TEST(BoundedQueue, DropOldestKeepsTheNewestAndCounts) {
  BoundedQueue<int> q(3, FullPolicy::kDropOldest);
  for (int i = 0; i < 5; ++i) {
    int v = i;
    EXPECT_TRUE(q.Push(v));
  }
  EXPECT_EQ(q.dropped(), 2);
  int v = -1;
  std::vector<int> got;
  while (q.TryPop(v)) got.push_back(v);
  EXPECT_EQ(got, (std::vector<int>{2, 3, 4}));
}

TEST(BoundedQueue, DropNewestRefusesAndCounts) {
  BoundedQueue<int> q(2, FullPolicy::kDropNewest);
  for (int i = 0; i < 4; ++i) {
    int v = i;
    EXPECT_EQ(q.Push(v), i < 2);
  }
  EXPECT_EQ(q.dropped(), 2);
  int v = -1;
  ASSERT_TRUE(q.TryPop(v));
  EXPECT_EQ(v, 0);
}

TEST(BoundedQueue, BlockWaitsForTheConsumerAndLosesNothing) {
  BoundedQueue<int> q(2, FullPolicy::kBlock);
  std::thread producer([&] {
    for (int i = 0; i < 1000; ++i) {
      int v = i;
      q.Push(v);
    }
    q.Close();
  });
  int v = 0, expect = 0;
  while (true) {
    if (!q.Pop(v, std::chrono::milliseconds(100))) {
      if (q.closed_and_empty()) break;
      continue;
    }
    EXPECT_EQ(v, expect++);
  }
  producer.join();
  EXPECT_EQ(expect, 1000);
  EXPECT_EQ(q.dropped(), 0);
}

TEST(BoundedQueue, SwapRecyclesBuffersWithoutAllocating) {
  BoundedQueue<std::vector<uint8_t>> q(2, FullPolicy::kDropOldest);
  std::vector<uint8_t> a(1000, 1), out;
  q.Push(a);  // a now holds the slot's old (empty) buffer
  EXPECT_TRUE(a.empty());
  ASSERT_TRUE(q.TryPop(out));
  EXPECT_EQ(out.size(), 1000u);
  const uint8_t* storage = out.data();
  q.Push(out);  // give the buffer back ...
  std::vector<uint8_t> again;
  ASSERT_TRUE(q.TryPop(again));
  EXPECT_EQ(again.data(), storage);  // ... and the same storage comes out
}

}  // namespace
}  // namespace kincal::daemon
