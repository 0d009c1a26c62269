// What kincal plan writes: plan.csv reads back through analyze's controls reader to the
// same controls, plan.json carries every motion's curve, and a symbolic link planted at
// plan.csv is replaced, not followed; what the plan gives robots within the prior is
// written and summarised.
#include "kincal/plan/plan_output.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "kincal/io/recording.h"

namespace kincal {
namespace {

namespace fs = std::filesystem;

// A differential drive known to 0.1 %, planned for 6 s.
struct SmallPlanCase {
  System sys = MakeSystem("diffdrive").value();
  Eigen::Vector3d p{0.03, 0.03, 0.3};
  Eigen::Matrix3d prior = Eigen::Vector3d(1e-6, 1e-6, 1e-4).asDiagonal();
  PlanOptions o;
  SmallPlanCase() {
    o.duration_s = 6.0;
    o.max_abs = {10.0, 10.0};
    o.max_accel = {30.0, 30.0};
  }
};

TEST(PlanOutput, CsvReadsBackAndJsonHasEveryMotion) {
  const SmallPlanCase c;
  const System& sys = c.sys;
  const Eigen::Vector3d& p = c.p;
  const Eigen::Matrix3d& prior = c.prior;
  const PlanOptions& o = c.o;
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

// What the plan gives robots within the prior: in plan.json (a plan that does not reach
// the targets there within the duration has no time and a speed-up of 0) and as one line
// of the summary, which names the robot where the plan does least well.
TEST(PlanOutput, TheRobotsWithinThePriorAreWrittenAndSummarised) {
  const SmallPlanCase c;
  const System& sys = c.sys;
  const PlanOptions& o = c.o;
  Motion plan;
  plan.name = "plan";
  plan.controls = ControlSignal(2, 0);
  plan.curve.t_s = {0.0};
  plan.curve.sigma = {Eigen::Vector3d(1e-3, 1e-3, 1e-2)};
  plan.curve.time_to_target_s = 4.0;
  plan.within_prior = {{"the design point", 6.0, 4.0},
                       {"r_l -3 sigma", 8.0, std::numeric_limits<double>::infinity()},
                       {"d +3 sigma", 9.0, 3.0}};
  EXPECT_EQ(LeastSpeedUp(plan), (std::pair<double, std::string>{0.0, "r_l -3 sigma"}));
  std::ostringstream summary;
  PrintPlanSummary(sys, o, plan, {}, summary);
  EXPECT_NE(summary.str().find("the plan is 0x to 3x as fast as the quickest usual motion there; "
                               "least at r_l -3 sigma (the plan not within 6 s, the usual motion "
                               "8 s)"),
            std::string::npos)
      << summary.str();
  const fs::path dir = fs::temp_directory_path() / ("kincal_plan_w" + std::to_string(::getpid()));
  fs::remove_all(dir);
  ASSERT_TRUE(WritePlanFiles(dir.string(), sys, c.p, c.prior, o, plan, {}).ok());
  std::ifstream jf(dir / "plan.json");
  const nlohmann::json j = nlohmann::json::parse(jf)["within_prior"];
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[0]["robot"], "the design point");
  EXPECT_DOUBLE_EQ(j[0]["speedup"].get<double>(), 1.5);
  EXPECT_TRUE(j[1]["plan_s"].is_null());
  EXPECT_EQ(j[1]["speedup"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(j[2]["usual_s"].get<double>(), 9.0);
  EXPECT_DOUBLE_EQ(j[2]["speedup"].get<double>(), 3.0);
  // Without them (kincald's guidance plans without usual motions): no line, an empty list.
  plan.within_prior.clear();
  std::ostringstream bare;
  PrintPlanSummary(sys, o, plan, {}, bare);
  EXPECT_EQ(bare.str().find("within_prior"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace kincal
