// What kincal plan writes: plan.csv reads back through analyze's controls reader to the
// same controls, plan.json carries every motion's curve, and a symbolic link planted at
// plan.csv is replaced, not followed.
#include "kincal/plan/plan_output.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "kincal/io/recording.h"

namespace kincal {
namespace {

namespace fs = std::filesystem;

TEST(PlanOutput, CsvReadsBackAndJsonHasEveryMotion) {
  const System sys = MakeSystem("diffdrive").value();
  const Eigen::Vector3d p(0.03, 0.03, 0.3);
  const Eigen::Matrix3d prior = Eigen::Vector3d(1e-6, 1e-6, 1e-4).asDiagonal();
  PlanOptions o;
  o.duration_s = 6.0;
  o.max_abs = {10.0, 10.0};
  o.max_accel = {30.0, 30.0};
  const auto ws = MakeArena(-1.0, -1.0, 1.0, 1.0);
  Motion plan;
  ASSERT_TRUE(PlanMotion(sys, p, prior, *ws, o, &plan).ok());
  const std::vector<Motion> usual = UsualMotions(sys, p, prior, *ws, o);

  const fs::path dir = fs::temp_directory_path() / ("kincal_plan_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path victim = dir / "victim.txt";
  std::ofstream(victim) << "keep\n";
  fs::create_symlink(victim, dir / "plan.csv");
  ASSERT_TRUE(WritePlanFiles(dir.string(), sys, p, prior, o, plan, usual).ok());
  EXPECT_FALSE(fs::is_symlink(dir / "plan.csv"));
  std::ifstream keep(victim);
  std::string line;
  std::getline(keep, line);
  EXPECT_EQ(line, "keep");

  std::ofstream(dir / "poses.csv") << "t,x,y,theta\n0,0,0,0\n";
  const Recording r =
      ReadCsvRecording((dir / "plan.csv").string(), (dir / "poses.csv").string(), sys.model())
          .value();
  ASSERT_EQ(r.controls.size(), plan.controls.size());
  for (size_t i = 0; i < plan.controls.size(); i += 7) {
    const int k = static_cast<int>(i);
    EXPECT_NEAR(r.controls.ValuesAt(k)[0], plan.controls.ValuesAt(k)[0], 1e-9);
    EXPECT_NEAR(r.controls.ValuesAt(k)[1], plan.controls.ValuesAt(k)[1], 1e-9);
  }
  std::ifstream jf(dir / "plan.json");
  const nlohmann::json j = nlohmann::json::parse(jf);
  EXPECT_EQ(j["params"].size(), 3u);
  EXPECT_EQ(j["usual"].size(), usual.size());
  EXPECT_EQ(j["plan"]["sigma"].size(), plan.curve.t_s.size());
  EXPECT_EQ(j["plan"]["path"].size(), plan.curve.t_s.size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace kincal
