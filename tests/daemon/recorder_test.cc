// The recorder: every event written and read back; live, a full queue drops and counts.
#include "daemon/recorder.h"

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
#include "kincal/io/lcm_log_reader.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

TEST(Recorder, EveryEventIsWrittenAndReadsBack) {
  const std::string path = TempPath("rec.lcm");
  {
    std::unique_ptr<Recorder> opened;
    ASSERT_TRUE(Recorder::Open(path, 64, FullPolicy::kBlock, 0.1, &opened).ok());
    Recorder& rec = *opened;
    std::vector<std::thread> producers;
    for (int t = 0; t < 3; ++t) {
      producers.emplace_back([&rec, t] {
        for (int i = 0; i < 500; ++i) {
          const int payload[2] = {t, i};
          rec.Write("CH" + std::to_string(t), 1000 + i, payload, sizeof(payload));
        }
      });
    }
    for (auto& p : producers) p.join();
    rec.Close();
    EXPECT_EQ(rec.written(), 1500);
    EXPECT_EQ(rec.lost(), 0);
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  std::array<int, 3> next{};
  int n = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    ASSERT_EQ(ev->datalen, 8);
    const int* p = static_cast<const int*>(ev->data);
    EXPECT_EQ(ev->channel, "CH" + std::to_string(p[0]));
    EXPECT_EQ(p[1], next[static_cast<size_t>(p[0])]++) << "per-producer order kept";
    ++n;
  }
  EXPECT_EQ(n, 1500);
}

TEST(Recorder, LiveModeCountsWhatAFullQueueDrops) {
  const std::string path = TempPath("rec_drop.lcm");
  std::unique_ptr<Recorder> opened;
  ASSERT_TRUE(Recorder::Open(path, 16, FullPolicy::kDropNewest, 1.0, &opened).ok());
  Recorder& rec = *opened;
  const std::vector<uint8_t> big(1 << 20, 7);
  for (int i = 0; i < 200; ++i) rec.Write("BIG", i, big.data(), big.size());
  rec.Close();
  EXPECT_EQ(rec.written() + rec.lost(), 200) << "every event is written or counted as lost";
}

// Reproduces issue 16 (item 8): --record followed a link planted at its path and
// overwrote the link's target.
TEST(Recorder, ALinkAtThePathIsRefusedNotFollowed) {
  const std::string victim = TempPath("rec_victim.txt");
  std::ofstream(victim) << "precious";
  const std::string path = TempPath("rec_link.lcm");
  std::filesystem::remove(path);
  std::filesystem::create_symlink(victim, path);
  std::unique_ptr<Recorder> opened;
  const Status s = Recorder::Open(path, 64, FullPolicy::kBlock, 0.1, &opened);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("symbolic link"), std::string::npos) << s.message();
  std::ifstream in(victim);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "precious");
}

}  // namespace
}  // namespace kincal::daemon
