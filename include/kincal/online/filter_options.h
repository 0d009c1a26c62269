// The online estimator's filter: which one, its noise, and when it restarts, gates and
// re-fits (kincald's `filter:` section).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "kincal/types.h"

namespace kincal {

struct FilterOptions {
  std::string type = "dd2";         // dd2 | ekf | ukf
  std::vector<double> control_psd;  // per control channel; empty: zeros
  std::array<double, kPoseDim> pose_psd{0.0, 0.0, 0.0};
  double max_pose_gap_s = 1.0;      // a longer gap starts a new run (pose reset)
  double params_rate_hz = 10.0;     // params_t publish rate (0: every update)
  double control_history_s = 10.0;  // control samples kept behind the filter
  double gate_nis = 16.27;          // innovation gate (chi^2, 3 dof, 99.9 %); 0: off
  int divergence_gated = 10;        // this many gated poses in a row: diverged, re-fit by batch
  double batch_window_s = 8.0;      // poses (and controls) the re-fit uses; <= control_history_s
  // Add pose process noise while the innovations run larger than predicted (model error),
  // and take it back when they are normal (kincal/estimation/noise_adaptation.h).
  bool adaptive_noise = true;
  bool IsValid(std::string* error) const;
};

}  // namespace kincal
