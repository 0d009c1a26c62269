// ReadLcmLog (src/io/lcm_log.cc): kincald's LCM logs read back as a recording, controls
// mapped onto the model's order by name; damaged ones read with warnings; a missing file
// is an error Status.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>

#include "io/io_test_util.h"
#include "kincal/io/recording.h"

namespace kincal {
namespace {

using testing::PutMessage;
class LcmLog : public testing::IoTest {};

TEST_F(LcmLog, ReadsBack) {
  const std::string path = (dir_ / "run.lcm").string();
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    for (int k = 0; k < 5; ++k) {
      kincal::controls_t c{};
      c.schema_version = 1;
      c.utime = 1'000'000 + k * 100'000;
      c.model = "unicycle";
      c.num_controls = 2;
      c.names = {"omega", "v"};
      c.values = {0.1 * k, 0.5};
      PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = 1'000'000 + k * 100'000 + 50'000;
      p.x = 0.05 * k;
      p.valid = 1;
      PutMessage(log, "KINCAL_POSE", p, p.utime);
    }
  }
  const Recording r = ReadLcmLog(path, *MakeModel("unicycle").value()).value();
  EXPECT_EQ(r.controls.size(), 5u);
  EXPECT_EQ(r.poses.size(), 5u);
  EXPECT_DOUBLE_EQ(r.origin_s, 1.0);
  EXPECT_EQ(r.controls.At(0.45)[0], 0.5);           // v, mapped by name
  EXPECT_NEAR(r.controls.At(0.45)[1], 0.4, 1e-12);  // omega
  EXPECT_NEAR(r.poses[2].z.x(), 0.1, 1e-12);
  const std::string missing = (dir_ / "none.lcm").string();
  const auto none = ReadLcmLog(missing, *MakeModel("unicycle").value());
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().message(),
            missing + ": cannot open the LCM log: No such file or directory");
}

TEST_F(LcmLog, DamagedIsReadWithWarnings) {
  // ReadLcmLog keeps the good events and reports the damage as warnings.
  const std::string path = (dir_ / "run.lcm").string();
  {
    lcm::LogFile log(path, "w");
    for (int k = 0; k < 4; ++k) {
      kincal::controls_t c{};
      c.schema_version = 1;
      c.utime = 1'000'000 + k * 100'000;
      c.model = "unicycle";
      c.num_controls = 2;
      c.names = {"v", "omega"};
      c.values = {0.5, 0.1};
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = c.utime + 50'000;
      p.valid = 1;
      PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
      PutMessage(log, "KINCAL_POSE", p, c.utime);
    }
  }
  std::ifstream in(path, std::ios::binary);
  std::string b(std::istreambuf_iterator<char>(in), {});
  in.close();
  Write("run.lcm", b.substr(0, b.size() - 5));  // the last pose cut short
  const Recording r = ReadLcmLog(path, *MakeModel("unicycle").value()).value();
  EXPECT_EQ(r.controls.size(), 4u);
  EXPECT_EQ(r.poses.size(), 3u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("cut short"), std::string::npos) << r.warnings[0];
}

}  // namespace
}  // namespace kincal
