// Simulation scenarios (config/sim_*.yaml): a true robot, optional hidden effects, the
// estimator's model and initial guess, command profile and camera timing. Read by
// `kincal simulate` and by kincald's simulated camera.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "kincal/sim/simulator.h"
#include "kincal/status.h"
#include "kincal/system.h"

namespace kincal {

// One-to-one image of the scenario YAML (see config/sim_*.yaml).
struct Scenario {
  std::string model = "diffdrive";
  std::map<std::string, double> truth;         // model + hidden-effect parameters
  std::vector<std::string> hidden_effects;     // simulated, not told to the estimator
  std::vector<std::string> estimator_effects;  // modelled by the estimator
  std::map<std::string, double> guess;         // initial guess (default: model defaults)
  double guess_sigma_fraction = 0.2;           // prior 1-sigma as a fraction of the guess
  double duration_s = 120.0;
  uint64_t seed = 1;
  std::string profile = "smooth";  // smooth | piecewise
  std::vector<double> control_low, control_high;
  double min_period_s = 2.0;
  double control_rate_hz = 50.0;
  FrameTimingOptions camera{30.0, 0.0, 0.0, 0.0};
  Eigen::Vector3d pose_sigma{0.001, 0.001, 0.005};  // m, m, rad
  std::string filter = "dd2";
  std::vector<double> control_psd;
  double report_every_s = 10.0;

  // Numbers in range: durations and rates > 0 (the duration at most kMaxDurationS), the
  // controls' low <= high per channel, the camera's timing valid. The file's numbers are
  // finite by the time this is asked (LoadScenario refuses others where it reads them).
  bool IsValid(std::string* error) const;
};

// The longest scenario (kincald's simulated camera runs at most as long: 30 days).
inline constexpr double kMaxScenarioDurationS = 30.0 * 86400.0;

// An error names the file, line and key (a number that is not finite among them), or the
// file and what Scenario::IsValid refuses.
StatusOr<Scenario> LoadScenario(const std::string& file);

// Parameter vector of `sys`: model defaults overridden by `values` (by name). An error names
// `what` and the unknown parameter, or one whose value is not finite.
StatusOr<VecN<kMaxState>> ParamsFrom(const System& sys, const std::map<std::string, double>& values,
                                     const std::string& what);

}  // namespace kincal
