// Scenario files: the shipped examples load into the typed struct; a bad key or value is
// named with file and line; parameters by name over the model's defaults.
#include "kincal/sim/scenario.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "source_dir.h"

namespace kincal {
namespace {

std::string Source(const std::string& rel) { return ::kincal::testing::SourceDir() + "/" + rel; }

std::string ScenarioLoadError(const std::string& path) {
  const StatusOr<Scenario> s = LoadScenario(path);
  return s.ok() ? std::string("no error") : s.status().message();
}

TEST(Scenario, ShippedExampleLoads) {
  const Scenario s = LoadScenario(Source("config/sim_diffdrive.yaml")).value();
  EXPECT_EQ(s.model, "diffdrive");
  EXPECT_GT(s.duration_s, 0.0);
  EXPECT_GT(s.camera.rate_hz, 0.0);
  EXPECT_FALSE(s.truth.empty());
}

TEST(Scenario, UnknownKeyIsNamedWithFileAndLine) {
  const std::string e = ScenarioLoadError(Source("tests/data/bad_scenario.yaml"));
  EXPECT_NE(e.find("bad_scenario.yaml:3: unknown key 'wheel_radius'"), std::string::npos) << e;
}

TEST(Scenario, NegativeDurationIsRejected) {
  const auto path = std::filesystem::temp_directory_path() / "kincal_scenario_duration.yaml";
  std::ofstream(path) << "model: unicycle\nduration_s: -5\n";
  const std::string e = ScenarioLoadError(path.string());
  std::filesystem::remove(path);
  EXPECT_NE(e.find("duration_s"), std::string::npos) << e;
}

TEST(Scenario, ParamsByNameOverTheModelsDefaults) {
  const System sys = MakeSystem("diffdrive").value();
  const VecN<kMaxState> p = ParamsFrom(sys, {{"d", 0.2}}, "truth").value();
  EXPECT_EQ(p[2], 0.2);
  EXPECT_EQ(p[0], sys.params()[0].default_value);
  EXPECT_FALSE(ParamsFrom(sys, {{"wheel", 1.0}}, "truth").ok());
}

}  // namespace
}  // namespace kincal
