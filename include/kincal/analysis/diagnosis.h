// The residual diagnosis: which regressors (what the robot was told to do) the prediction
// errors correlate with, and how strongly an effect's signature is present. Used by
// `kincal analyze` on prediction windows; the vocabulary (kincal/signature.h) is the one
// effects declare and the daemon's online model check measures.
#pragma once

#include <string>
#include <vector>

#include "kincal/signature.h"

namespace kincal {

// The prediction error of one window at its horizon, in the body frame of the measured
// end pose.
struct ResidualPoint {
  double t_s;  // window start, seconds since the recording origin
  bool heldout;
  double along, cross, heading;  // m, m, rad
};

struct DiagnosisTerm {
  std::string component;  // along, cross, heading (ComponentName)
  std::string regressor;  // RegressorName
  double r = 0.0;         // correlation over windows (for const: mean over RMS, a bias)
  double z = 0.0;         // r * sqrt(effective number of independent windows)
  ResidualComponent component_id = ResidualComponent::kAlong;
  Regressor regressor_id = Regressor::kConst;
};

// Every (component, regressor) term over the fit windows (not the held-out ones), strongest
// |z| first. `regressors` holds one entry per point; windows of `horizon_s` overlap, so the
// effective number of independent windows is the fit span over one horizon. Empty with
// fewer than 10 fit windows.
std::vector<DiagnosisTerm> Diagnose(const std::vector<ResidualPoint>& points,
                                    const std::vector<RegressorValues>& regressors,
                                    double horizon_s);

// The strongest |z| among the terms of a signature (0 when none was measured).
double SignatureZ(const std::vector<SignatureTerm>& signature,
                  const std::vector<DiagnosisTerm>& diagnosis);

}  // namespace kincal
