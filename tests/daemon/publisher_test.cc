// The publisher: a message goes to LCM and to the log, or to one of them when asked; raw
// bytes likewise; an LCM URL or a log path that cannot be opened is named.
#include "daemon/publisher.h"

#include <gtest/gtest.h>

#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <vector>

#include "daemon/daemon_test_util.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

struct PublisherHeard {
  std::map<std::string, int> count;
  void On(const lcm::ReceiveBuffer*, const std::string& channel) { ++count[channel]; }
};

TEST(Publisher, EachMessageGoesWhereItIsSent) {
  const std::string path = TempPath("publisher.lcm");
  LcmOptions lcm_opt;
  lcm_opt.url = "memq://";
  RecordOptions rec;
  rec.path = path;
  Publisher pub;
  ASSERT_TRUE(pub.Open(lcm_opt, rec, 16, /*lossless=*/true).ok());
  PublisherHeard heard;
  pub.lcm()->subscribe(".*", &PublisherHeard::On, &heard);
  kincal::pose_t pose{};
  pose.schema_version = 1;
  pose.x = 1.25;
  pub.Publish("POSE", 100, pose);                         // both
  pub.Publish("LOG_ONLY", 200, pose, /*network=*/false);  // the log alone
  const char raw[3] = {'a', 'b', 'c'};
  pub.PublishRaw("RAW_NET", raw, sizeof(raw));   // LCM alone
  pub.Record("RAW_LOG", 300, raw, sizeof(raw));  // the log alone
  while (pub.lcm()->handleTimeout(0) > 0) {
  }
  pub.CloseLog();
  pub.CloseLog();  // idempotent
  EXPECT_EQ(heard.count, (std::map<std::string, int>{{"POSE", 1}, {"RAW_NET", 1}}));

  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  std::vector<std::pair<std::string, int64_t>> events;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    events.emplace_back(ev->channel, ev->timestamp);
    if (ev->channel == "POSE") {
      kincal::pose_t back;
      ASSERT_EQ(back.decode(ev->data, 0, ev->datalen), ev->datalen);
      EXPECT_EQ(back.x, 1.25);
    }
  }
  EXPECT_EQ(events, (std::vector<std::pair<std::string, int64_t>>{
                        {"POSE", 100}, {"LOG_ONLY", 200}, {"RAW_LOG", 300}}));
}

TEST(Publisher, WithoutARecordingNothingIsLogged) {
  LcmOptions lcm_opt;
  lcm_opt.url = "memq://";
  Publisher pub;
  ASSERT_TRUE(pub.Open(lcm_opt, RecordOptions{}, 16, false).ok());
  EXPECT_EQ(pub.recorder(), nullptr);
  const char raw[1] = {'x'};
  pub.Record("RAW_LOG", 1, raw, 1);  // no log: nothing happens
  pub.CloseLog();
}

TEST(Publisher, WhatCannotBeOpenedIsNamed) {
  LcmOptions bad;
  bad.url = "nosuchprovider://x";
  Publisher a;
  const Status s = a.Open(bad, RecordOptions{}, 16, false);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("nosuchprovider://x"), std::string::npos) << s.message();

  LcmOptions lcm_opt;
  lcm_opt.url = "memq://";
  RecordOptions rec;
  rec.path = TempPath("no_such_dir") + "/run.lcm";
  Publisher b;
  const Status r = b.Open(lcm_opt, rec, 16, false);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find(rec.path), std::string::npos) << r.message();
}

}  // namespace
}  // namespace kincal::daemon
