// The capture stage with a scripted source (no camera): every frame reaches the queue in
// order and, when recording, the log as a frame_t; the queue is closed when the source
// ends; a live device that fails is reopened and its error is shown, then cleared; a
// source that cannot reopen ends the stage; `stop` ends a source that only times out.
#include "daemon/capture_stage.h"

#include <gtest/gtest.h>

#include <deque>
#include <kincal/frame_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "daemon/daemon_test_util.h"

namespace kincal::daemon {
namespace {

using test_util::TempPath;

// Plays a script of statuses: kFrame hands over an 8x4 grey frame numbered in order.
class ScriptedSource final : public FrameSource {
 public:
  ScriptedSource(std::deque<SourceStatus> script, bool can_reopen)
      : script_(std::move(script)), can_reopen_(can_reopen) {}
  std::string name() const override { return "scripted"; }
  Status Start() override { return {}; }
  SourceStatus Next(Frame* f, int, std::string* error) override {
    if (script_.empty()) return SourceStatus::kEnd;
    const SourceStatus s = script_.front();
    script_.pop_front();
    if (s == SourceStatus::kError) *error = "the cable came out";
    if (s == SourceStatus::kTimeout) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (s != SourceStatus::kFrame) return s;
    f->width = 8;
    f->height = 4;
    f->stride = 8;
    f->format = PixelFormat::kGrey;
    f->data.assign(32, static_cast<uint8_t>(next_));
    f->sequence = next_;
    f->utime = 1'000'000 + 33'000 * next_;
    ++next_;
    return SourceStatus::kFrame;
  }
  void Stop() override {}
  Status Reopen() override {
    ++reopens_;
    return {};
  }
  SourceCapabilities capabilities() const override {
    SourceCapabilities c;
    c.can_reopen = can_reopen_;
    return c;
  }
  int reopens_ = 0;

 private:
  std::deque<SourceStatus> script_;
  bool can_reopen_;
  int64_t next_ = 0;
};

struct Rig {
  Publisher publisher;
  BoundedQueue<Frame> queue{64, FullPolicy::kBlock};
  CounterSet counters;
  std::vector<std::string> errors;
  explicit Rig(const std::string& record_path = "") {
    LcmOptions lcm;
    lcm.url = "memq://";
    RecordOptions rec;
    rec.path = record_path;
    EXPECT_TRUE(publisher.Open(lcm, rec, 64, /*lossless=*/true).ok());
  }
  CaptureStage Stage(FrameSource* s) {
    return CaptureStage(s, {"KINCAL_FRAME", false, FrameEncoding::kRaw}, &publisher, &queue,
                        &counters, [this](const std::string& e) { errors.push_back(e); });
  }
  std::vector<int64_t> Sequences() {
    std::vector<int64_t> out;
    Frame f;
    while (queue.TryPop(f)) out.push_back(f.sequence);
    return out;
  }
};

constexpr SourceStatus F = SourceStatus::kFrame;

TEST(CaptureStage, EveryFrameReachesTheQueueAndTheLog) {
  const std::string path = TempPath("capture.lcm");
  {
    Rig rig(path);
    ScriptedSource src({F, F, SourceStatus::kTimeout, F, F, F}, false);
    std::atomic<bool> stop{false};
    rig.Stage(&src).Run(stop);
    EXPECT_EQ(rig.Sequences(), (std::vector<int64_t>{0, 1, 2, 3, 4}));
    EXPECT_TRUE(rig.queue.closed_and_empty());
    EXPECT_EQ(rig.counters.frames_captured.load(), 5);
    EXPECT_TRUE(rig.errors.empty());
    rig.publisher.CloseLog();
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  int frames = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    ASSERT_EQ(ev->channel, "KINCAL_FRAME");
    kincal::frame_t m;
    ASSERT_GT(m.decode(ev->data, 0, ev->datalen), 0);
    EXPECT_EQ(m.utime, 1'000'000 + 33'000 * frames);
    EXPECT_EQ(m.width, 8);
    ++frames;
  }
  EXPECT_EQ(frames, 5);
}

TEST(CaptureStage, AFailedDeviceIsReopenedAndItsErrorCleared) {
  Rig rig;
  ScriptedSource src({F, SourceStatus::kError, F, F}, /*can_reopen=*/true);
  std::atomic<bool> stop{false};
  rig.Stage(&src).Run(stop);
  EXPECT_EQ(src.reopens_, 1);
  EXPECT_EQ(rig.counters.source_restarts.load(), 1);
  EXPECT_EQ(rig.errors, (std::vector<std::string>{"the cable came out", ""}));
  EXPECT_EQ(rig.Sequences(), (std::vector<int64_t>{0, 1, 2}));
}

TEST(CaptureStage, ASourceThatCannotReopenEndsTheStage) {
  Rig rig;
  ScriptedSource src({F, SourceStatus::kError, F}, /*can_reopen=*/false);
  std::atomic<bool> stop{false};
  rig.Stage(&src).Run(stop);
  EXPECT_EQ(src.reopens_, 0);
  EXPECT_EQ(rig.errors, std::vector<std::string>{"the cable came out"});
  EXPECT_EQ(rig.Sequences(), std::vector<int64_t>{0});
  EXPECT_TRUE(rig.queue.closed_and_empty());
}

TEST(CaptureStage, StopEndsASourceThatOnlyTimesOut) {
  Rig rig;
  ScriptedSource src(std::deque<SourceStatus>(100000, SourceStatus::kTimeout), false);
  std::atomic<bool> stop{false};
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    stop.store(true);
  });
  rig.Stage(&src).Run(stop);
  stopper.join();
  EXPECT_TRUE(rig.queue.closed_and_empty());
  EXPECT_EQ(rig.counters.frames_captured.load(), 0);
}

}  // namespace
}  // namespace kincal::daemon
