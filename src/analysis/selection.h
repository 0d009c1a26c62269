// Effect selection: the candidate effects for a model, and one candidate tried on top of
// the effects accepted so far (multi-start fit, quasi-BIC, held-out gain, identifiability).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "analysis/baseline_fit.h"
#include "analysis/evaluation.h"
#include "analysis/windows.h"
#include "kincal/analysis/analyze.h"
#include "kincal/effect.h"

namespace kincal::analysis {

// Effect specs to try on the model: every registered effect that applies (and, for
// channel-wise effects, one per channel), the user's list, or none.
std::vector<std::string> Candidates(const KinematicModel& m, const AnalyzeOptions& o);

FitReport MakeReport(const System& sys, const Fit& f, const Evaluation& e,
                     const std::vector<std::string>& effects, int fit_windows);

// Where the selection stands: the effects accepted so far and their fit.
struct SelectionState {
  std::vector<std::shared_ptr<const Effect>> effects;
  Fit fit;
  Evaluation eval;
  std::vector<DiagnosisTerm> diagnosis;
};

// One candidate tried on top of the current state.
struct Tried {
  EffectTrial trial;
  Fit fit;
  Evaluation eval;
  std::vector<std::shared_ptr<const Effect>> effects;
  bool ok = false;  // fitted, and every parameter identifiable
};

// Fits `spec` on top of `current` from several starts (the current parameters with the
// effect's defaults, the command lag for timing effects, +-2 sigma for a single new
// parameter) and scores it. False when the effect cannot be made or fitted (with a user's
// effect list, a bad spec throws AnalysisError instead).
bool TryEffect(const std::string& spec, int round, const SelectionState& current, const Dataset& d,
               const std::shared_ptr<const KinematicModel>& model, double command_lag,
               const AnalyzeOptions& o, Tried* out);

}  // namespace kincal::analysis
