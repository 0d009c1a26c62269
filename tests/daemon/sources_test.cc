// The frame-source factory (src/daemon/sources.cc): the source the config names, declaring
// what it can do; a device that cannot be opened is a status naming it and errno's text.
// The replay and simulated sources have their own tests (replay_source_test.cc,
// sim_source_test.cc).
#include "daemon/sources.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>

#include "daemon/daemon_test_util.h"
#include "source_dir.h"

namespace kincal::daemon {
namespace {

using test_util::Counted;
using test_util::Drain;
using test_util::SimConfig;
using test_util::TempPath;

TEST(Sources, V4l2DeviceThatIsNotThereIsAStatusWithErrno) {
  DaemonConfig c = SimConfig(1.0);
  c.source = SourceKind::kV4l2;
  c.v4l2.device = "/dev/kincal-no-such-video";
  auto src = MakeSource(c, LoadVisionSetup(c).value(), nullptr, nullptr).value();
  ASSERT_NE(src, nullptr);
  EXPECT_TRUE(src->capabilities().can_reopen);
  EXPECT_FALSE(src->capabilities().carries_controls);
  const Status s = src->Start();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("/dev/kincal-no-such-video"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("No such file or directory"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace kincal::daemon
