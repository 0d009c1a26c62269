// Checkpoints: written atomically, read back exactly, exported as YAML.
#include "kincal/io/checkpoint.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "temp_path.h"

namespace kincal {
namespace {

using ::kincal::testing::TempPath;

Checkpoint Good() {
  Checkpoint c;
  c.model = "diffdrive";
  c.filter = "dd2";
  c.names = {"r_l", "r_r", "d"};
  c.units = {"m", "m", "m"};
  c.values = {0.031, 0.0313, 0.148};
  c.covariance = Eigen::Matrix3d::Identity() * 1e-8;
  return c;
}

// Why a checkpoint is refused (empty: accepted).
std::string Refusal(const Checkpoint& c) {
  std::string error;
  return CheckpointIsValid(c, &error) ? "" : error;
}

TEST(Checkpoint, ImplausibleValuesAndCovariancesAreRefusedByName) {
  EXPECT_EQ(Refusal(Good()), "");
  Checkpoint c = Good();
  c.values[0] = 1e308;  // crashed the divergence re-fit
  EXPECT_NE(Refusal(c).find("value of 'r_l' (1e+308 m) is not plausible"), std::string::npos)
      << Refusal(c);
  c = Good();
  c.values[2] = 2e13;
  EXPECT_NE(Refusal(c).find("value of 'd'"), std::string::npos) << Refusal(c);
  c = Good();
  c.values[1] = -0.03;  // a radius below its bound
  EXPECT_NE(Refusal(c).find(">= "), std::string::npos) << Refusal(c);
  c = Good();
  c.covariance(1, 1) = -1e-8;
  EXPECT_NE(Refusal(c).find("variance of 'r_r'"), std::string::npos) << Refusal(c);
  c = Good();
  c.covariance(2, 2) = 0.0;
  EXPECT_NE(Refusal(c).find("variance of 'd'"), std::string::npos) << Refusal(c);
  c = Good();
  c.covariance(0, 0) = 3.6e-17;  // sigma 6e-9 m: the filter would never move
  EXPECT_NE(Refusal(c).find("variance of 'r_l'"), std::string::npos) << Refusal(c);
  c = Good();
  c.covariance(0, 1) = 1e-8;  // not symmetric
  EXPECT_NE(Refusal(c).find("not symmetric"), std::string::npos) << Refusal(c);
  c = Good();
  c.covariance(0, 1) = c.covariance(1, 0) = 2e-8;  // |correlation| > 1
  EXPECT_NE(Refusal(c).find("not positive definite"), std::string::npos) << Refusal(c);
  c = Good();
  c.model = "bogus";
  EXPECT_NE(Refusal(c).find("bogus"), std::string::npos) << Refusal(c);
  c = Good();
  c.names[2] = "wheelbase";
  EXPECT_NE(Refusal(c).find("is 'wheelbase', expected 'd'"), std::string::npos) << Refusal(c);
}

// robot.fixed: a held parameter has zero variance and no correlation, which a free one may
// not have; it round-trips as held and exports as held.
TEST(Checkpoint, AHeldParameterHasNoVarianceAndRoundTrips) {
  Checkpoint c = Good();
  c.covariance(0, 2) = c.covariance(2, 0) = 1e-9;
  c.covariance(2, 2) = 2e-8;
  MarkHeld({"d", "not_a_parameter"}, &c);
  EXPECT_EQ(c.held, std::vector<std::string>{"d"});
  EXPECT_EQ(c.covariance(2, 2), 0.0);
  EXPECT_EQ(c.covariance(0, 2), 0.0);
  EXPECT_EQ(Refusal(c), "");
  const std::string path = TempPath("held.json");
  ASSERT_TRUE(WriteCheckpoint(path, c).ok());
  StatusOr<Checkpoint> r = ReadCheckpoint(path);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->held, c.held);
  EXPECT_EQ(r->covariance, c.covariance);
  std::ostringstream yaml;
  WriteExportYaml(yaml, *r, path);
  EXPECT_NE(yaml.str().find("  d: {value: 0.148, sigma: 0, unit: \"m\", held: true}"),
            std::string::npos)
      << yaml.str();
  Checkpoint bad = c;
  bad.covariance(1, 2) = bad.covariance(2, 1) = 1e-9;
  EXPECT_NE(Refusal(bad).find("'d' is held but has a variance or a correlation"), std::string::npos)
      << Refusal(bad);
  bad = c;
  bad.held = {"wheelbase"};
  EXPECT_NE(Refusal(bad).find("held parameter 'wheelbase' is not a parameter"), std::string::npos)
      << Refusal(bad);
  bad = c;
  bad.held.clear();  // the zero variance of an unheld parameter is still refused
  EXPECT_NE(Refusal(bad).find("variance of 'd'"), std::string::npos) << Refusal(bad);
}

TEST(Checkpoint, FindsAParameterByName) {
  Checkpoint c = Good();
  c.covariance(1, 1) = 4e-8;
  double value = 0, sigma = 0;
  ASSERT_TRUE(FindParameter(c, "r_r", &value, &sigma));
  EXPECT_EQ(value, 0.0313);
  EXPECT_DOUBLE_EQ(sigma, 2e-4);
  EXPECT_FALSE(FindParameter(c, "wheelbase", &value, &sigma));
  EXPECT_EQ(value, 0.0313);  // untouched
}

TEST(Checkpoint, AMissingFileIsAStatusWithErrnoText) {
  const StatusOr<Checkpoint> r = ReadCheckpoint(TempPath("no_such_checkpoint.json"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(
      r.status().message().find("no_such_checkpoint.json: cannot open checkpoint: No such file"),
      std::string::npos)
      << r.status().message();
}

TEST(Checkpoint, ReadRefusesAnImplausibleFileNamingIt) {
  Checkpoint c = Good();
  c.values[0] = 1e200;
  const std::string path = TempPath("ck_big.json");
  ASSERT_TRUE(WriteCheckpoint(path, c).ok());
  StatusOr<Checkpoint> r = ReadCheckpoint(path);
  ASSERT_FALSE(r.ok()) << "accepted r_l = 1e200";
  EXPECT_NE(r.status().message().find(path + ": value of 'r_l'"), std::string::npos)
      << r.status().message();
}

// Reproduces issue 16 (item 12): a unit holding '"' and a newline made YAML that did not
// parse.
TEST(Checkpoint, ExportEscapesEveryString) {
  Checkpoint c = Good();
  c.units[0] = "m\"\nx: 1";
  c.effects = {"actuator_lag[omega_l]"};
  std::ostringstream yaml;
  WriteExportYaml(yaml, c, "a\nb");
  const std::string y = yaml.str();
  EXPECT_NE(y.find("unit: \"m\\\"\\nx: 1\"}"), std::string::npos) << y;
  EXPECT_NE(y.find("effects: [\"actuator_lag[omega_l]\"]"), std::string::npos) << y;
  EXPECT_NE(y.find("from a?b\n"), std::string::npos) << y;
  EXPECT_EQ(std::count(y.begin(), y.end(), '\n'), 14) << y;  // no line was split
}

TEST(Checkpoint, RoundTripsAtomicallyAndExportsYaml) {
  Checkpoint c;
  c.model = "diffdrive";
  c.filter = "dd2";
  c.utime = 1234567;
  c.update_count = 42;
  c.names = {"r_l", "r_r", "d"};
  c.units = {"m", "m", "m"};
  c.values = {0.031, 0.0313, 0.148};
  c.covariance = Eigen::Matrix3d::Identity() * 1e-8;
  c.covariance(0, 1) = c.covariance(1, 0) = 3e-9;
  const std::string path = TempPath("ck.json");
  ASSERT_TRUE(WriteCheckpoint(path, c).ok());
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const Checkpoint r = ReadCheckpoint(path).value();
  EXPECT_EQ(r.names, c.names);
  EXPECT_EQ(r.values, c.values);
  EXPECT_EQ(r.covariance, c.covariance);
  std::ostringstream yaml;
  WriteExportYaml(yaml, r, path);
  EXPECT_NE(yaml.str().find("  r_r: {value: 0.0313, sigma: 0.0001, unit: \"m\"}"),
            std::string::npos)
      << yaml.str();
  std::ofstream(path) << "{\"format\": \"kincal-checkpoint\", \"version\": 1, \"model\": 3}";
  const StatusOr<Checkpoint> bad = ReadCheckpoint(path);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find(path + ": "), std::string::npos) << bad.status().message();
}

// A batch calibration's checkpoint says whose it is, through the file and the export; an
// older checkpoint without a source is the filter's; an unknown source is refused.
TEST(Checkpoint, SaysWhoseEstimateItIs) {
  Checkpoint c = Good();
  c.source = "batch";
  c.batch_sequence = 4;
  c.batch_poses = 1800;
  const std::string path = TempPath("ck_batch.json");
  ASSERT_TRUE(WriteCheckpoint(path, c).ok());
  const Checkpoint r = ReadCheckpoint(path).value();
  EXPECT_EQ(r.source, "batch");
  EXPECT_EQ(r.batch_sequence, 4);
  EXPECT_EQ(r.batch_poses, 1800);
  std::ostringstream yaml;
  WriteExportYaml(yaml, r, path);
  EXPECT_NE(yaml.str().find("# the batch calibration (batch 4, 1800 poses"), std::string::npos)
      << yaml.str();
  EXPECT_NE(yaml.str().find("\nsource: batch\n"), std::string::npos) << yaml.str();

  std::string text;
  {
    std::ifstream in(path);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto erase_key = [&](const std::string& key) {
    const size_t at = text.find("\"" + key + "\"");
    ASSERT_NE(at, std::string::npos) << key;
    text.erase(at, text.find('\n', at) - at + 1);
  };
  erase_key("source");
  erase_key("batch_sequence");
  erase_key("batch_poses");
  std::ofstream(path) << text;
  EXPECT_EQ(ReadCheckpoint(path).value().source, "filter");
  c.source = "guess";
  ASSERT_TRUE(WriteCheckpoint(path, c).ok());
  const StatusOr<Checkpoint> guess = ReadCheckpoint(path);
  ASSERT_FALSE(guess.ok()) << "an unknown source was read";
  EXPECT_NE(guess.status().message().find("source is 'guess'"), std::string::npos)
      << guess.status().message();
}

TEST(Checkpoint, WritesNeverFollowALinkAndLeaveNoTemporaryOnFailure) {
  const std::string victim = TempPath("victim.txt");
  std::ofstream(victim) << "precious";
  const std::string path = TempPath("ck_link.json");
  std::filesystem::remove(path + ".tmp");
  std::filesystem::create_symlink(victim, path + ".tmp");  // planted where the temporary goes
  ASSERT_TRUE(WriteCheckpoint(path, Good()).ok());
  std::ifstream in(victim);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "precious");
  EXPECT_EQ(ReadCheckpoint(path).value().values, Good().values);
  // A folder that does not exist: a status naming the file and errno's text.
  const Status missing = WriteCheckpoint(TempPath("no_such_dir") + "/ck.json", Good());
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("No such file or directory"), std::string::npos)
      << missing.message();
  // Not finite: nothing written, nothing left behind.
  Checkpoint nan = Good();
  nan.values[0] = std::nan("");
  const std::string nan_path = TempPath("ck_nan.json");
  EXPECT_FALSE(WriteCheckpoint(nan_path, nan).ok());
  EXPECT_FALSE(std::filesystem::exists(nan_path));
  EXPECT_FALSE(std::filesystem::exists(nan_path + ".tmp"));
}

}  // namespace
}  // namespace kincal
