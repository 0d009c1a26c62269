// BatchTier: when batches start (the first once the run spans first_s, then every every_s
// of data time, or growth x the span fitted when that is longer) and when their results apply
// (lossless: at a fixed data time after the start, so that a replay decides the same every time);
// at shutdown, one more over everything; the fit is analyze's on the same data.
#include "kincal/online/batch_tier.h"

#include <gtest/gtest.h>

#include "analysis/analysis_test_util.h"

namespace kincal {
namespace {

// A recording fed to the tier as the filter stage would, up to t_s; the results that
// came back on the way.
struct Fed {
  explicit Fed(Recording r) : rec(std::move(r)) {}
  Recording rec;
  size_t next_control = 0, next_pose = 0;
  std::vector<std::pair<double, BatchCalibration>> results;  // (data time s, result)
  void Until(BatchTier* tier, double t_s) {
    const TimeNs t = SecondsToNs(t_s);
    while (next_pose < rec.poses.size() && rec.poses[next_pose].t_ns <= t) {
      const TimeNs tp = rec.poses[next_pose].t_ns;
      for (; next_control < rec.controls.size(); ++next_control) {
        const TimeNs tc = rec.controls.ToNs(rec.controls.TimeAt(static_cast<int>(next_control)));
        if (tc > tp) break;
        const auto& v = rec.controls.ValuesAt(static_cast<int>(next_control));
        tier->AddControl(tc, std::span<const double>(v.data(), 2));
      }
      tier->AddPose(tp, rec.poses[next_pose].z);
      if (auto r = tier->OnPose(tp)) results.emplace_back(NsToSeconds(tp), std::move(*r));
      ++next_pose;
    }
  }
};

BatchTierOptions Lossless(bool auto_effects) {
  BatchTierOptions o;
  o.lossless = true;
  o.auto_effects = auto_effects;
  o.first_s = 30.0;
  o.every_s = 40.0;
  return o;
}

TEST(BatchTier, StartsOnScheduleAndAppliesAtFixedDataTimes) {
  BatchTier tier(Lossless(true), "unicycle", {}, {{"k_v", 1.0}, {"k_omega", 1.0}}, 2,
                 std::make_unique<InlineBatchRunner>());
  Fed fed(testing::UnicycleRecording(120.0, {"time_offset"}, {{"delay_s", 0.2}}, 6));
  fed.Until(&tier, 29.9);
  EXPECT_FALSE(tier.running());  // the run spans less than first_s
  fed.Until(&tier, 30.1);
  ASSERT_TRUE(tier.running());
  EXPECT_EQ(tier.started(), 1);
  fed.Until(&tier, 34.9);
  EXPECT_TRUE(fed.results.empty());  // lossless: not before apply_after_s of data
  fed.Until(&tier, 35.1);
  ASSERT_EQ(fed.results.size(), 1u);
  const BatchCalibration& first = fed.results[0].second;
  ASSERT_TRUE(first.ok) << first.error;
  EXPECT_EQ(first.sequence, 1);
  EXPECT_EQ(first.accepted, std::vector<std::string>{"time_offset"}) << first.evidence;
  EXPECT_NEAR(NsToSeconds(first.data_end_ns), 30.0, 0.06);  // the data up to its start
  EXPECT_NEAR(fed.results[0].first, 35.0, 0.06);
  fed.Until(&tier, 69.9);
  EXPECT_EQ(tier.started(), 1);  // every_s after the first start
  fed.Until(&tier, 70.1);
  EXPECT_EQ(tier.started(), 2);
  fed.Until(&tier, 120.0);
  EXPECT_EQ(fed.results.size(), 3u);  // started at 30, 70 and 110 s
  // At shutdown: one over everything.
  const auto last = tier.Finish(SecondsToNs(120.0));
  ASSERT_EQ(last.size(), 1u);
  EXPECT_EQ(last[0].sequence, 4);
  EXPECT_EQ(last[0].num_poses, static_cast<int>(fed.rec.poses.size()));
  // The last batch is kincal analyze on the same data, with the same start.
  AnalyzeOptions o;
  o.model = "unicycle";
  o.init = {{"k_v", 1.0}, {"k_omega", 1.0}};
  const AnalyzeResult offline = Analyze(fed.rec, o).value();
  ASSERT_TRUE(last[0].ok) << last[0].error;
  ASSERT_EQ(last[0].params.size(), offline.after.params.size());
  for (size_t i = 0; i < offline.after.params.size(); ++i) {
    EXPECT_NEAR(last[0].params[i].value, offline.after.params[i].value,
                0.05 * offline.after.params[i].sigma)
        << offline.after.params[i].name;
  }
}

// A long run: each batch refits everything, so once growth x the fitted span exceeds
// every_s the batches spread out (a --fast replay of hours waits for O(log T) of them,
// not O(T); the soak test replays 64 h).
TEST(BatchTier, LongRunsSpaceBatchesByAFractionOfTheirSpan) {
  BatchTierOptions o = Lossless(false);
  o.first_s = 10.0;
  o.every_s = 10.0;
  o.growth = 0.5;
  BatchTier tier(o, "unicycle", {}, {}, 2, std::make_unique<InlineBatchRunner>());
  Fed fed(testing::UnicycleRecording(110.0, {}, {}, 9));
  // Starts at 10, 20 (max(10, 5)), 30 (max(10, 10)), 45, 67.5 and 101.25 s.
  const std::vector<std::pair<double, int>> expected = {
      {9.9, 0},  {10.1, 1}, {19.9, 1}, {20.1, 2},  {29.9, 2},  {30.1, 3}, {44.9, 3},
      {45.1, 4}, {67.4, 4}, {67.6, 5}, {101.1, 5}, {101.4, 6}, {110.0, 6}};
  for (const auto& [t_s, started] : expected) {
    fed.Until(&tier, t_s);
    EXPECT_EQ(tier.started(), started) << "at " << t_s << " s";
  }
  o.growth = -0.1;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("growth"), std::string::npos) << error;
}

// A stop (kincald's SIGTERM): the running batch is cut short, no new one starts while the
// queues drain, and Finish fits everything.
TEST(BatchTier, AStopStartsNoNewBatchAndFinishFitsEverything) {
  BatchTier tier(Lossless(false), "unicycle", {}, {}, 2, std::make_unique<InlineBatchRunner>());
  Fed fed(testing::UnicycleRecording(120.0, {}, {}, 10));
  fed.Until(&tier, 30.1);
  ASSERT_EQ(tier.started(), 1);
  tier.CancelRunning();
  fed.Until(&tier, 120.0);
  EXPECT_EQ(tier.started(), 1) << "no batch after the stop";
  EXPECT_LE(fed.results.size(), 1u);  // the first, unless it ended before the cancel
  const auto last = tier.Finish(SecondsToNs(120.0));
  ASSERT_FALSE(last.empty());
  EXPECT_TRUE(last.back().ok) << last.back().error;
  EXPECT_FALSE(last.back().cancelled);
  EXPECT_EQ(last.back().num_poses, static_cast<int>(fed.rec.poses.size()));
  EXPECT_EQ(tier.started(), 2);
}

TEST(BatchTier, WithoutAutoTheDeclaredModelIsFittedAndNothingAccepted) {
  BatchTier tier(Lossless(false), "unicycle", {}, {}, 2, std::make_unique<InlineBatchRunner>());
  Fed fed(testing::UnicycleRecording(60.0, {"time_offset"}, {{"delay_s", 0.2}}, 7));
  fed.Until(&tier, 60.0);
  ASSERT_EQ(fed.results.size(), 1u);
  EXPECT_TRUE(fed.results[0].second.ok) << fed.results[0].second.error;
  EXPECT_TRUE(fed.results[0].second.accepted.empty());
  EXPECT_EQ(fed.results[0].second.params.size(), 2u);
}

TEST(BatchTier, DisabledDoesNothing) {
  BatchTierOptions o = Lossless(false);
  o.enabled = false;
  BatchTier tier(o, "unicycle", {}, {}, 2, std::make_unique<InlineBatchRunner>());
  Fed fed(testing::UnicycleRecording(60.0, {}, {}, 8));
  fed.Until(&tier, 60.0);
  EXPECT_TRUE(fed.results.empty());
  EXPECT_TRUE(tier.Finish(SecondsToNs(60.0)).empty());
  EXPECT_EQ(tier.store().num_poses(), 0u);
}

// --resume: a batch calibration of this run fused with the resumed one of earlier data.
TEST(BatchTier, FusesWithTheResumedCalibrationByInformation) {
  BatchCalibration r;
  r.ok = true;
  r.effects = {"time_offset"};
  r.params = {{"k_v", "1", 0.90, 0.02, 0}, {"k_omega", "1", 0.80, 0.01, 0}};
  r.covariance = Eigen::Vector2d(4e-4, 1e-4).asDiagonal();
  Checkpoint resumed;
  resumed.source = "batch";
  resumed.batch_sequence = 7;
  resumed.effects = {"time_offset"};
  resumed.names = {"k_v", "k_omega"};
  resumed.values = {0.94, 0.80};
  resumed.covariance = Eigen::Vector2d(4e-4, 3e-4).asDiagonal();
  std::string why;
  const BatchCalibration f = FusedWithResumed(r, resumed, &why);
  EXPECT_NE(f.prior.find("batch 7"), std::string::npos) << f.prior;
  EXPECT_NEAR(f.params[0].value, 0.92, 1e-12);  // equal weights: the mean
  EXPECT_NEAR(f.params[0].sigma, std::sqrt(2e-4), 1e-12);
  EXPECT_NEAR(f.covariance(1, 1), 1.0 / (1.0 / 1e-4 + 1.0 / 3e-4), 1e-15);
  // Other effects: the batch alone, and why.
  resumed.effects.clear();
  const BatchCalibration alone = FusedWithResumed(r, resumed, &why);
  EXPECT_TRUE(alone.prior.empty());
  EXPECT_EQ(alone.params[0].value, 0.90);
  EXPECT_NE(why.find("other parameters or effects"), std::string::npos) << why;
}

// robot.fixed: the batch holds a parameter (zero variance); the free ones are still fused
// with the resumed calibration, and the held one keeps the value it is held at.
TEST(BatchTier, FusesTheFreeParametersWhenOneIsHeld) {
  BatchCalibration r;
  r.ok = true;
  r.params = {{"k_v", "1", 0.90, 0.02, 0},
              {"wheelbase", "m", 0.33, 0.0, 0},
              {"k_steer", "1", 0.60, 0.01, 0}};
  r.covariance = Eigen::Vector3d(4e-4, 0.0, 1e-4).asDiagonal();
  Checkpoint resumed;
  resumed.source = "batch";
  resumed.batch_sequence = 3;
  resumed.names = {"k_v", "wheelbase", "k_steer"};
  resumed.values = {0.94, 0.31, 0.62};
  resumed.covariance = Eigen::Vector3d(4e-4, 0.0, 1e-4).asDiagonal();
  std::string why;
  const BatchCalibration f = FusedWithResumed(r, resumed, &why);
  EXPECT_NE(f.prior.find("batch 3"), std::string::npos) << why;
  EXPECT_NEAR(f.params[0].value, 0.92, 1e-12);
  EXPECT_NEAR(f.params[0].sigma, std::sqrt(2e-4), 1e-12);
  EXPECT_NEAR(f.params[2].value, 0.61, 1e-12);
  EXPECT_EQ(f.params[1].value, 0.33);  // held: this run's value, not the resumed one
  EXPECT_EQ(f.params[1].sigma, 0.0);
  EXPECT_EQ(f.covariance(1, 1), 0.0);
  EXPECT_EQ(f.covariance(0, 1), 0.0);
  // A parameter the resumed run held but this one estimates: not the same calibration.
  r.covariance(1, 1) = 1e-6;
  r.params[1].sigma = 1e-3;
  const BatchCalibration alone = FusedWithResumed(r, resumed, &why);
  EXPECT_TRUE(alone.prior.empty());
  EXPECT_NE(why.find("wheelbase"), std::string::npos) << why;
}

TEST(BatchTier, OptionsAreChecked) {
  std::string error;
  BatchTierOptions o;
  EXPECT_TRUE(o.IsValid(&error));
  o.every_s = 0.5;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("every_s"), std::string::npos);
}

}  // namespace
}  // namespace kincal
