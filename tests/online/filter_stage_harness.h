// Drives a FilterStage directly with a simulated robot's controls and poses, in time order,
// as the filter thread would (no threads, no camera): the fast way to test the stage
// against ground truth, with or without effects the estimator was not told about.
#pragma once

#include <algorithm>
#include <deque>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "kincal/io/recording.h"
#include "kincal/online/batch_calibration.h"
#include "kincal/online/filter_stage.h"
#include "kincal/sim/scenario.h"
#include "kincal/sim/simulator.h"
#include "test_util.h"

namespace kincal::online_test {

// An arbitrary realtime origin, as a live run's stamps would have.
inline constexpr int64_t kUtimeOrigin = 1'700'000'000'000'000;

struct StageScenario {
  std::string model = "diffdrive";
  std::vector<std::string> hidden;  // effects the truth has
  std::map<std::string, double> truth;
  std::vector<std::string> declared;    // effects the estimator is told about
  std::map<std::string, double> guess;  // model defaults otherwise
  std::map<std::string, double> fixed;  // robot.fixed
  double guess_sigma_fraction = 0.15;
  double duration_s = 60.0;
  double camera_hz = 30.0;
  Eigen::Vector3d pose_sigma{0.001, 0.001, 0.005};
  uint64_t seed = 1;
  std::vector<size_t> outliers;  // poses (by index) moved 0.5 m: a reflection, a wrong match
  bool auto_effects = false;     // robot.effects: auto
};

struct StageRun {
  std::vector<kincal::params_t> params;
  std::vector<kincal::model_check_t> checks;
  std::vector<kincal::calibration_t> calibrations;
  OnlineCounts counters;
  Checkpoint filter_estimate;             // the filter's last
  std::optional<Checkpoint> calibration;  // the batch calibration in force at the end
  Checkpoint estimate;  // what kincald would checkpoint: the calibration, else the filter's
  // The last published value of a parameter.
  double Final(const std::string& name) const {
    for (size_t i = 0; i < estimate.names.size(); ++i) {
      if (estimate.names[i] == name) return estimate.values[i];
    }
    return std::nan("");
  }
  double FinalSigma(const std::string& name) const {
    for (size_t i = 0; i < estimate.names.size(); ++i) {
      if (estimate.names[i] == name) {
        const int k = static_cast<int>(i);
        return std::sqrt(estimate.covariance(k, k));
      }
    }
    return std::nan("");
  }
};

// The scenario's robot simulated (smooth random controls in the model's usual range, at
// 50 Hz) as the samples the filter thread receives.
struct Samples {
  std::vector<ControlSample> controls;
  std::vector<PoseSample> poses;
};
inline Samples Simulate(const StageScenario& sc) {
  const System truth = MakeSystem(sc.model, sc.hidden).value();
  testing::ModelScenario range;
  for (const auto& m : testing::AllModelScenarios()) {
    if (m.model == sc.model) range = m;
  }
  std::mt19937_64 rng(sc.seed);
  const auto params = ParamsFrom(truth, sc.truth, "truth").value();
  const testing::SimData d = testing::Simulate(truth, params, range.lo, range.hi, sc.duration_s,
                                               sc.camera_hz, sc.pose_sigma, rng);
  Samples out;
  const int nc = truth.num_controls();
  for (int i = 0; i < static_cast<int>(d.controls.size()); ++i) {
    ControlSample c;
    c.utime = kUtimeOrigin + PipelineNsToUtime(d.controls.ToNs(d.controls.TimeAt(i)));
    c.receive_utime = c.utime;
    const auto& v = d.controls.ValuesAt(i);
    std::copy(v.begin(), v.begin() + nc, c.values.begin());
    out.controls.push_back(c);
  }
  for (size_t k = 0; k < d.meas.size(); ++k) {
    PoseSample p;
    p.utime = kUtimeOrigin + PipelineNsToUtime(d.meas[k].t_ns);
    p.sequence = static_cast<int64_t>(k);
    p.valid = true;
    p.xytheta = d.meas[k].z;
    p.covariance = d.meas[k].R;
    if (std::find(sc.outliers.begin(), sc.outliers.end(), k) != sc.outliers.end()) {
      p.xytheta.x() += 0.5;
    }
    out.poses.push_back(p);
  }
  return out;
}

// The same samples as a recording for `kincal analyze` (poses' times relative to the first
// control).
inline Recording ToRecording(const Samples& s, int num_controls) {
  Recording rec;
  rec.source = "simulated";
  const TimeNs origin = UtimeToPipelineNs(s.controls.front().utime);
  rec.controls = ControlSignal(num_controls, origin);
  for (const auto& c : s.controls) {
    rec.controls.Append(
        UtimeToPipelineNs(c.utime),
        std::span<const double>(c.values.data(), static_cast<size_t>(num_controls)));
  }
  for (const auto& p : s.poses) rec.poses.push_back({UtimeToPipelineNs(p.utime), p.xytheta});
  return rec;
}

inline FilterPrior Prior(const StageScenario& sc, const System& est) {
  return GuessedPrior(est, sc.guess, sc.guess_sigma_fraction, sc.fixed, "test");
}

// Collects what the stage publishes.
inline FilterOutputs Collect(StageRun* run) {
  FilterOutputs out;
  out.params = [run](int64_t, const kincal::params_t& m) { run->params.push_back(m); };
  out.model_check = [run](int64_t, const kincal::model_check_t& m) { run->checks.push_back(m); };
  out.estimate = [run](const Checkpoint& ck) { run->filter_estimate = ck; };
  out.calibration = [run](int64_t, const kincal::calibration_t& m, const Checkpoint* good) {
    run->calibrations.push_back(m);
    if (good != nullptr) run->calibration = *good;
  };
  out.checkpoint_due = [] {};
  return out;
}

// Runs the filter stage on the simulated samples, each pose once the controls up to its
// time are queued (as the filter thread hands them over), with `options` (effects from
// the scenario).
inline StageRun RunStageOn(const Samples& samples, const StageScenario& sc,
                           FilterStageOptions options) {
  const System est = MakeSystem(sc.model, sc.declared).value();
  options.effects = sc.declared;
  options.auto_effects = sc.auto_effects;
  options.fixed = sc.fixed;
  options.lossless = true;  // one thread feeds the stage: decisions at fixed data times
  StageRun run;
  OnlineCounters counters;
  std::deque<ControlSample> queued;
  FilterStage stage(
      est, options, Prior(sc, est),
      [&](ControlSample* c) {
        if (queued.empty()) return false;
        *c = queued.front();
        queued.pop_front();
        return true;
      },
      Collect(&run), &counters, std::make_unique<InlineBatchRunner>());
  size_t next_control = 0;
  for (const PoseSample& p : samples.poses) {
    for (;
         next_control < samples.controls.size() && samples.controls[next_control].utime <= p.utime;
         ++next_control) {
      queued.push_back(samples.controls[next_control]);
    }
    stage.DrainControls(0);
    stage.AddPose(p, 0);
  }
  stage.Finish();
  run.counters = counters.LoadOnline();
  run.estimate = run.calibration ? *run.calibration : run.filter_estimate;
  return run;
}

inline StageRun RunStage(const StageScenario& sc, FilterStageOptions options) {
  return RunStageOn(Simulate(sc), sc, std::move(options));
}

// The daemon's defaults for the stage, as the shipped simulated config sets them.
inline FilterStageOptions DefaultStageOptions() {
  FilterStageOptions o;
  o.filter.pose_psd = {1e-7, 1e-7, 1e-6};
  o.filter.max_pose_gap_s = 0.5;
  return o;
}

}  // namespace kincal::online_test
