// Runs: several recordings (files, logs, a CSV's 'run' column) joined as the runs of one
// recording, in order, never one run running into the next.
#include <gtest/gtest.h>

#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>
#include <kincal/run_t.hpp>

#include "io/io_test_util.h"

namespace kincal {
namespace {

class Runs : public testing::IoTest {};

// A part of 2 s on its own epoch (origin_s), controls and poses every 0.5 s.
Recording Part(double origin_s, const std::string& source) {
  Recording r;
  r.source = source;
  r.origin_s = origin_s;
  r.controls = ControlSignal(2, 0);
  for (int k = 0; k <= 4; ++k) {
    const std::array<double, 2> u = {0.1 * k, 0.0};
    r.controls.Append(SecondsToNs(0.5 * k), u);
    r.poses.push_back({SecondsToNs(0.5 * k), Eigen::Vector3d(0.1 * k, 0, 0)});
  }
  r.stats.pose_rows = r.stats.control_rows = 5;
  return r;
}

TEST_F(Runs, PartsInTimeOrderKeepTheirTimes) {
  const Recording rec = JoinRuns({Part(100.0, "a"), Part(110.0, "b"), Part(120.0, "c")}).value();
  ASSERT_EQ(rec.runs.size(), 3u);
  EXPECT_EQ(rec.runs[1].start_ns, SecondsToNs(10.0));
  EXPECT_EQ(rec.runs[2].source, "c");
  EXPECT_EQ(rec.poses.size(), 15u);
  EXPECT_EQ(rec.poses[5].t_ns, SecondsToNs(10.0));
  EXPECT_EQ(rec.stats.pose_rows, 15);
  EXPECT_TRUE(rec.warnings.empty());
  EXPECT_EQ(RunOf(rec, SecondsToNs(9.9)), 0);
  EXPECT_EQ(RunOf(rec, SecondsToNs(10.0)), 1);
  EXPECT_EQ(RunOf(rec, SecondsToNs(25.0)), 2);
}

// Each bag on its own clock (all starting at 0), or given out of order: moved to start
// kRunGapS after the previous run, and said.
TEST_F(Runs, PartsThatOverlapAreMovedAfterThePreviousAndSaid) {
  const Recording rec = JoinRuns({Part(0.0, "a"), Part(0.0, "b"), Part(-50.0, "c")}).value();
  ASSERT_EQ(rec.runs.size(), 3u);
  EXPECT_EQ(rec.runs[1].start_ns, SecondsToNs(2.0 + kRunGapS));
  EXPECT_EQ(rec.runs[2].start_ns, SecondsToNs(2.0 + kRunGapS + 2.0 + kRunGapS));
  ASSERT_EQ(rec.warnings.size(), 2u);
  EXPECT_NE(rec.warnings[0].find("b: starts 3 s too early"), std::string::npos) << rec.warnings[0];
  for (size_t i = 1; i < rec.poses.size(); ++i) EXPECT_GT(rec.poses[i].t_ns, rec.poses[i - 1].t_ns);
}

TEST_F(Runs, DifferentControlChannelsAreAnError) {
  Recording odd = Part(10.0, "odd.csv");
  odd.controls = ControlSignal(3, 0);
  EXPECT_FALSE(JoinRuns({Part(0.0, "a"), odd}).ok());
}

// A 'run' column, anywhere in the header, makes each run its own part.
TEST_F(Runs, CsvRunColumnInAnyPositionGivesRuns) {
  const Recording rec =
      ReadCsvRecording(
          Write("c.csv", "run,t,omega,v\n1,0,0,1\n1,1,0,1\n1,2,0,1\n2,0,0,2\n2,1,0,2\n"),
          Write("p.csv",
                "t,x,y,theta,run\n0,0,0,0,1\n1,1,0,0,1\n2,2,0,0,1\n0,5,5,0,2\n1,7,5,0,2\n"),
          *MakeModel("unicycle").value())
          .value();
  ASSERT_EQ(rec.runs.size(), 2u);
  EXPECT_EQ(rec.runs[1].start_ns, SecondsToNs(2.0 + kRunGapS));
  EXPECT_EQ(rec.poses.size(), 5u);
  EXPECT_EQ(rec.controls.At(rec.controls.ToSeconds(rec.runs[1].start_ns))[0], 2.0);
  EXPECT_NE(rec.source.find("c.csv + "), std::string::npos);
}

TEST_F(Runs, BadRunColumnsAreNamedErrors) {
  const auto model = MakeModel("unicycle").value();
  auto error = [&](const std::string& c, const std::string& p) -> std::string {
    const StatusOr<Recording> r = ReadCsvRecording(Write("c.csv", c), Write("p.csv", p), *model);
    return r.ok() ? std::string("no error") : r.status().message();
  };
  EXPECT_NE(error("t,v,omega,run\n0,1,0,one\n", "t,x,y,theta,run\n0,0,0,0,1\n")
                .find("c.csv:2: column 'run': expected an integer run number, got 'one'"),
            std::string::npos);
  EXPECT_NE(error("t,v,omega,run\n0,1,0,1\n1,1,0,1\n0,1,0,2\n", "t,x,y,theta,run\n0,0,0,0,1\n")
                .find("run 2 has controls but no poses"),
            std::string::npos);
  EXPECT_NE(
      error("t,v,omega,run\n0,1,0,1\n", "t,x,y,theta\n0,0,0,0\n").find("has a 'run' column and"),
      std::string::npos);
  EXPECT_NE(error("t,v,omega,run\n0,1,0,1\n", "t,x,y,theta,run\n0,0,0,0,1\n0,1,0,0,7\n")
                .find("run 7 has poses but no controls"),
            std::string::npos);
}

// `kincal import` of several bags marks each run's start with a kincal.run_t.
TEST_F(Runs, LcmLogRunMarkersGiveRuns) {
  const std::string path = (dir_ / "runs.lcm").string();
  {
    lcm::LogFile log(path, "w");
    for (int run = 0; run < 2; ++run) {
      const int64_t t0 = 1'000'000 + run * 10'000'000;
      kincal::run_t r{};
      r.schema_version = 1;
      r.utime = t0;
      r.index = run;
      r.source = "bag" + std::to_string(run);
      testing::PutMessage(log, "KINCAL_RUN", r, t0);
      for (int k = 0; k < 3; ++k) {
        kincal::controls_t c{};
        c.schema_version = 1;
        c.utime = t0 + k * 100'000;
        c.model = "unicycle";
        c.num_controls = 2;
        c.names = {"v", "omega"};
        c.values = {1.0, 0.0};
        testing::PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
        kincal::pose_t p{};
        p.schema_version = 1;
        p.utime = c.utime;
        p.valid = 1;
        p.x = 0.1 * k;
        testing::PutMessage(log, "KINCAL_POSE", p, p.utime);
      }
    }
  }
  const Recording rec = ReadLcmLog(path, *MakeModel("unicycle").value()).value();
  ASSERT_EQ(rec.runs.size(), 2u);
  EXPECT_EQ(rec.runs[0].start_ns, 0);
  EXPECT_EQ(rec.runs[1].start_ns, SecondsToNs(10.0));
  EXPECT_EQ(rec.runs[1].source, "bag1");
}

}  // namespace
}  // namespace kincal
