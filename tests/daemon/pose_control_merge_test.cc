#include "daemon/pose_control_merge.h"

#include <gtest/gtest.h>

#include <thread>

#include "daemon/batch_worker.h"
#include "online/filter_stage_harness.h"

namespace kincal::daemon {
namespace {

using online_test::StageRun;
using online_test::StageScenario;

StageScenario Scenario() {
  StageScenario sc;
  sc.truth = {{"r_l", 0.0310}, {"r_r", 0.0313}, {"d", 0.148}};
  sc.guess = {{"r_l", 0.034}, {"r_r", 0.029}, {"d", 0.160}};
  sc.duration_s = 20;
  return sc;
}

// Runs the merge on its own thread while this one queues every pose first and the
// controls 50 ms later: in lossless mode the poses must wait for their controls.
StageRun RunMerged(const StageScenario& sc, bool lossless) {
  const System est = MakeSystem(sc.model, sc.declared).value();
  auto samples = online_test::Simulate(sc);
  BoundedQueue<PoseSample> poses(samples.poses.size(), FullPolicy::kBlock);
  BoundedQueue<ControlSample> controls(samples.controls.size(), FullPolicy::kBlock);
  std::atomic<bool> controls_done{false}, stop{false};
  StageRun run;
  OnlineCounters counters;
  FilterStage stage(
      est, online_test::DefaultStageOptions(), online_test::Prior(sc, est),
      [&](ControlSample* c) { return controls.TryPop(*c); }, online_test::Collect(&run), &counters,
      std::make_unique<BatchWorker>(/*background=*/false));
  MergeInputs in;
  in.poses = &poses;
  in.controls = &controls;
  in.controls_done = &controls_done;
  in.stop = &stop;
  in.lossless = lossless;
  in.max_control_delay_ns = SecondsToNs(60.0);
  in.max_pending_poses = samples.poses.size();
  std::thread merge([&] { RunPoseControlMerge(&stage, in); });
  for (auto& p : samples.poses) poses.Push(p);
  poses.Close();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (auto& c : samples.controls) controls.Push(c);
  controls_done.store(true);
  merge.join();
  run.counters = counters.LoadOnline();
  run.estimate = run.calibration ? *run.calibration : run.filter_estimate;
  return run;
}

TEST(PoseControlMerge, PosesWaitForTheirControlsAndGiveTheInOrderResult) {
  const StageScenario sc = Scenario();
  const StageRun in_order = online_test::RunStage(sc, online_test::DefaultStageOptions());
  const StageRun merged = RunMerged(sc, /*lossless=*/true);
  ASSERT_FALSE(merged.estimate.names.empty());
  EXPECT_EQ(merged.counters.updates, in_order.counters.updates);
  for (size_t i = 0; i < in_order.estimate.values.size(); ++i) {
    EXPECT_DOUBLE_EQ(merged.estimate.values[i], in_order.estimate.values[i])
        << in_order.estimate.names[i];
  }
  for (const auto& [name, truth] : sc.truth) {
    EXPECT_NEAR(merged.Final(name), truth, 3 * merged.FinalSigma(name)) << name;
  }
}

}  // namespace
}  // namespace kincal::daemon
