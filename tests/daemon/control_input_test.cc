#include "daemon/control_input.h"

#include <gtest/gtest.h>

#include <kincal/controls_t.hpp>

#include "kincal/system.h"
#include "lcm_round_trip.h"

namespace kincal::daemon {
namespace {

using ::kincal::testing::Encoded;

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
  const System sys = MakeSystem("diffdrive").value();
  Publisher publisher;  // not opened: nothing is published or recorded
  BoundedQueue<ControlSample> queue{16, FullPolicy::kDropOldest};
  CounterSet counters;
};

TEST(ControlReceiver, QueuesAValidMessageInTheModelsChannelOrder) {
  Fixture f;
  ControlReceiver r(f.sys.model(), ControlStamp::kReceive, "C", &f.publisher, &f.queue,
                    &f.counters);
  const auto buf = Encoded(DiffDrive(1.5, -2.5));
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
  ControlReceiver r(f.sys.model(), ControlStamp::kSender, "C", &f.publisher, &f.queue, &f.counters);
  const auto buf = Encoded(DiffDrive(1, 1));
  r.OnMessage(buf.data(), buf.size(), 777);
  ControlSample s;
  ASSERT_TRUE(f.queue.TryPop(s));
  EXPECT_EQ(s.utime, 1234);
}

TEST(ControlReceiver, MapsTheSendersClockOntoTheReceiveClockAndReportsTheJitter) {
  Fixture f;
  ControlReceiver r(f.sys.model(), ControlStamp::kMapped, "C", &f.publisher, &f.queue, &f.counters);
  EXPECT_EQ(r.timing().jitter_p95_ms, -1.0) << "not measured before a message";
  // Sender clock 1234 us; received 10 ms late, then 2 ms late 20 ms of sender time later:
  // the second fixes the floor, 8 ms of jitter measured in the first.
  kincal::controls_t m = DiffDrive(1, 1);
  auto buf = Encoded(m);
  r.OnMessage(buf.data(), buf.size(), 1'000'000 + 10'000);
  m.sender_utime = 1234 + 20'000;
  buf = Encoded(m);
  r.OnMessage(buf.data(), buf.size(), 1'000'000 + 22'000);
  ControlSample a, b;
  ASSERT_TRUE(f.queue.TryPop(a));
  ASSERT_TRUE(f.queue.TryPop(b));
  EXPECT_EQ(a.utime, 1'010'000);  // nothing better known yet
  EXPECT_EQ(b.utime, 1'002'000 + 20'000);
  EXPECT_NEAR(r.timing().jitter_max_ms, 0.0, 1e-9) << "each was the floor when it came";
  // A message without a sender stamp keeps its receive stamp, and is counted.
  m.sender_utime = 0;
  buf = Encoded(m);
  r.OnMessage(buf.data(), buf.size(), 1'050'000);
  ControlSample c;
  ASSERT_TRUE(f.queue.TryPop(c));
  EXPECT_EQ(c.utime, 1'050'000);
  EXPECT_EQ(r.timing().without_sender_stamp, 1);
}

TEST(ControlReceiver, RejectsAndNamesWhatIsWrong) {
  Fixture f;
  ControlReceiver r(f.sys.model(), ControlStamp::kReceive, "C", &f.publisher, &f.queue,
                    &f.counters);
  kincal::controls_t wrong_model = DiffDrive(1, 1);
  wrong_model.model = "unicycle";
  auto buf = Encoded(wrong_model);
  r.OnMessage(buf.data(), buf.size(), 1);
  EXPECT_NE(r.last_reject().find("controls for model 'unicycle', expected 'diffdrive'"),
            std::string::npos)
      << r.last_reject();
  kincal::controls_t not_finite = DiffDrive(std::nan(""), 1);
  buf = Encoded(not_finite);
  r.OnMessage(buf.data(), buf.size(), 2);
  const uint8_t garbage[7] = {1, 2, 3, 4, 5, 6, 7};
  r.OnMessage(garbage, sizeof garbage, 3);
  // Finite but no wheel turns at 10^5 rad/s: a unit mistake or garbage (issue 16).
  buf = Encoded(DiffDrive(1e5, 1));
  r.OnMessage(buf.data(), buf.size(), 4);
  EXPECT_NE(r.last_reject().find("control 'omega_l' = 100000.000000: expected a finite value "
                                 "within +-10000.000000 rad/s"),
            std::string::npos)
      << r.last_reject();
  EXPECT_EQ(f.counters.messages_rejected.load(), 4);
  EXPECT_EQ(f.counters.controls_received.load(), 0);
  EXPECT_EQ(f.queue.size(), 0u);
}

}  // namespace
}  // namespace kincal::daemon
