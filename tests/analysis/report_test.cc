// The analyze report on its own (no fit): WriteAnalysisReport writes residuals.csv,
// report.html and report.json with the result's numbers; ReadReportEstimate reads the final
// estimate back; a folder that cannot be made and every broken report are named errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "kincal/analysis/analyze.h"
#include "temp_path.h"

namespace kincal {
namespace {

using kincal::testing::TempPath;

AnalyzeResult Result() {
  AnalyzeResult r;
  r.model = "unicycle";
  r.source = "robot.lcm";
  r.before.params = {{"k_v", "1", 1.0, 0.01, 0.005}, {"k_omega", "1", 0.9, 0.02, 0.01}};
  r.after = r.before;
  r.after.effects = {"time_offset"};
  r.after.params.push_back({"delay_s", "s", 0.21, 0.004, 0.002});
  r.after.heldout = {0.006, 0.02, 40};
  EffectTrial t;
  t.name = "time_offset";
  t.round = 1;
  t.accepted = true;
  t.params = {{"delay_s", "s", 0.21, 0.004, 0.002}};
  t.heldout_gain = 0.4;
  r.trials = {t};
  r.residual_steps = {{"before", {{1.0, false, 0.01, -0.02, 0.003}, {2.0, true, 0.0, 0.01, 0.0}}},
                      {"+time_offset", {{1.0, false, 0.001, -0.002, 0.0003}}}};
  return r;
}

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Report, TheThreeFilesHoldTheResult) {
  const std::string dir = TempPath("report_ok");
  ASSERT_TRUE(WriteAnalysisReport(Result(), dir).ok());
  const auto j = nlohmann::json::parse(Read(dir + "/report.json"));
  EXPECT_EQ(j["model"], "unicycle");
  EXPECT_EQ(j["after"]["effects"][0], "time_offset");
  EXPECT_DOUBLE_EQ(j["after"]["params"]["delay_s"]["value"].get<double>(), 0.21);
  EXPECT_DOUBLE_EQ(j["after"]["params"]["delay_s"]["sigma"].get<double>(), 0.004);
  EXPECT_DOUBLE_EQ(j["after"]["heldout"]["pos_rms_m"].get<double>(), 0.006);
  EXPECT_TRUE(j["effects"][0]["accepted"].get<bool>());
  const std::string csv = Read(dir + "/residuals.csv");
  EXPECT_EQ(csv,
            "step,t_s,heldout,along_m,cross_m,heading_rad\n"
            "before,1,0,0.01,-0.02,0.003\n"
            "before,2,1,0,0.01,0\n"
            "+time_offset,1,0,0.001,-0.002,0.0003\n");
  EXPECT_NE(Read(dir + "/report.html").find("</html>"), std::string::npos);
}

TEST(Report, TheEstimateReadsBack) {
  const std::string dir = TempPath("report_back");
  ASSERT_TRUE(WriteAnalysisReport(Result(), dir).ok());
  ReportEstimate e;
  ASSERT_TRUE(ReadReportEstimate(dir + "/report.json", &e).ok());
  EXPECT_EQ(e.model, "unicycle");
  EXPECT_EQ(e.source, "robot.lcm");
  EXPECT_EQ(e.effects, std::vector<std::string>{"time_offset"});
  ASSERT_EQ(e.names.size(), 3u);
  for (size_t i = 0; i < e.names.size(); ++i) {
    if (e.names[i] != "delay_s") continue;
    EXPECT_DOUBLE_EQ(e.values[i], 0.21);
    EXPECT_DOUBLE_EQ(e.sigmas[i], 0.004);
    EXPECT_EQ(e.units[i], "s");
  }
}

TEST(Report, AFolderThatCannotBeMadeIsAnError) {
  const std::string file = TempPath("report_in_the_way");
  std::ofstream(file) << "x";
  const Status s = WriteAnalysisReport(Result(), file + "/sub");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(file + "/sub"), std::string::npos) << s.message();
}

TEST(Report, ABrokenReportIsNamed) {
  ReportEstimate e;
  const std::string missing = TempPath("no_report.json");
  EXPECT_EQ(ReadReportEstimate(missing, &e).message(), missing + ": cannot open for reading");
  const std::string not_json = TempPath("not_json.json");
  std::ofstream(not_json) << "{model: ";
  EXPECT_NE(ReadReportEstimate(not_json, &e).message().find(not_json + ": not JSON"),
            std::string::npos);
  const std::string no_after = TempPath("no_after.json");
  std::ofstream(no_after) << R"({"model": "unicycle"})";
  EXPECT_NE(ReadReportEstimate(no_after, &e).message().find("after.params"), std::string::npos);
  const std::string bad_param = TempPath("bad_param.json");
  std::ofstream(bad_param)
      << R"({"model": "unicycle", "after": {"effects": [], "params": {"k_v": {"value": "x"}}}})";
  EXPECT_EQ(ReadReportEstimate(bad_param, &e).message(),
            bad_param + ": after.params.k_v: expected {value, sigma, unit}");
}

}  // namespace
}  // namespace kincal
