#include "daemon/control_input.h"

#include <gtest/gtest.h>

#include <kincal/controls_t.hpp>

#include "kincal/system.h"

namespace kincal::daemon {
namespace {

std::vector<uint8_t> Encode(const kincal::controls_t& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

kincal::controls_t DiffDrive(double left, double right) {
  kincal::controls_t m;
  m.schema_version = 1;
  m.utime = 5;
  m.sender_utime = 1234;
  m.model = "diffdrive";
  m.num_controls = 2;
  m.names = {"omega_r", "omega_l"};  // any order: matched by name
  m.values = {right, left};
  return m;
}

struct Fixture {
  const System sys = MakeSystem("diffdrive");
  Publisher publisher;  // not opened: nothing is published or recorded
  BoundedQueue<ControlSample> queue{16, FullPolicy::kDropOldest};
  CounterSet counters;
};

TEST(ControlReceiver, QueuesAValidMessageInTheModelsChannelOrder) {
  Fixture f;
  ControlReceiver r(f.sys.model(), /*use_sender_stamp=*/false, "C", &f.publisher, &f.queue,
                    &f.counters);
  const auto buf = Encode(DiffDrive(1.5, -2.5));
  r.OnMessage(buf.data(), buf.size(), 777);
  ControlSample s;
  ASSERT_TRUE(f.queue.TryPop(s));
  EXPECT_EQ(s.utime, 777);
  EXPECT_EQ(s.sender_utime, 1234);
  EXPECT_DOUBLE_EQ(s.values[0], 1.5);  // omega_l first, as the model lists it
  EXPECT_DOUBLE_EQ(s.values[1], -2.5);
  EXPECT_EQ(f.counters.controls_received.load(), 1);
}

TEST(ControlReceiver, UsesTheSendersStampWhenConfigured) {
  Fixture f;
  ControlReceiver r(f.sys.model(), /*use_sender_stamp=*/true, "C", &f.publisher, &f.queue,
                    &f.counters);
  const auto buf = Encode(DiffDrive(1, 1));
  r.OnMessage(buf.data(), buf.size(), 777);
  ControlSample s;
  ASSERT_TRUE(f.queue.TryPop(s));
  EXPECT_EQ(s.utime, 1234);
}

TEST(ControlReceiver, RejectsAndNamesWhatIsWrong) {
  Fixture f;
  ControlReceiver r(f.sys.model(), false, "C", &f.publisher, &f.queue, &f.counters);
  kincal::controls_t wrong_model = DiffDrive(1, 1);
  wrong_model.model = "unicycle";
  auto buf = Encode(wrong_model);
  r.OnMessage(buf.data(), buf.size(), 1);
  EXPECT_NE(r.last_reject().find("controls for model 'unicycle', expected 'diffdrive'"),
            std::string::npos)
      << r.last_reject();
  kincal::controls_t not_finite = DiffDrive(std::nan(""), 1);
  buf = Encode(not_finite);
  r.OnMessage(buf.data(), buf.size(), 2);
  const uint8_t garbage[7] = {1, 2, 3, 4, 5, 6, 7};
  r.OnMessage(garbage, sizeof garbage, 3);
  EXPECT_EQ(f.counters.messages_rejected.load(), 3);
  EXPECT_EQ(f.counters.controls_received.load(), 0);
  EXPECT_EQ(f.queue.size(), 0u);
}

}  // namespace
}  // namespace kincal::daemon
