// Effect selection: the candidate effects for a model, and one candidate tried on top of
// the effects accepted so far (multi-start fit, quasi-BIC, held-out gain, identifiability).
#pragma once

#include <Eigen/Core>
#include <map>
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
// True when `candidate` is an effect of the same kind as `accepted` on a channel it
// already acts on ("actuator_lag[omega]" after "actuator_lag"): a second copy's parameters
// trade off with the first's, so it is not a candidate.
bool Repeats(const std::string& candidate, const std::string& accepted);

FitReport MakeReport(const System& sys, const Fit& f, const Evaluation& e,
                     const std::vector<std::string>& effects, int fit_windows);

// Where the selection stands: the effects accepted so far and their fit, and each
// candidate's own parameters as the last round estimated them (warm starts).
struct SelectionState {
  std::vector<std::shared_ptr<const Effect>> effects;
  Fit fit;
  Evaluation eval;
  std::vector<DiagnosisTerm> diagnosis;
  std::map<std::string, Eigen::VectorXd> warm;
};

// One candidate tried on top of the current state.
struct Tried {
  EffectTrial trial;
  Fit fit;
  Evaluation eval;
  std::vector<std::shared_ptr<const Effect>> effects;
  bool ok = false;  // fitted, and every parameter identifiable
};

// A candidate screened: fitted on the screening windows (every few fit windows) from
// several starts.
struct Screened {
  std::string spec;
  std::shared_ptr<const KinematicModel> model;
  std::vector<std::shared_ptr<const Effect>> effects;
  Fit fit;  // on d.screen_meas, no covariance
  bool ok = false;
};

// Fits `spec` on top of `current` on the screening windows from several starts (the
// current parameters with the effect's defaults, or with its parameters of the last round
// when it was tried before; the command lag for timing effects; +-2 sigma for a single new
// parameter tried for the first time). False when the effect cannot be made or combined
// (a user's effect list, `user_list`, is checked before the selection: a bad spec there is
// a bug).
// Each solve runs on one thread: candidates are screened in parallel instead.
bool ScreenEffect(const std::string& spec, const SelectionState& current, const Dataset& d,
                  const std::shared_ptr<const KinematicModel>& model, double command_lag,
                  bool user_list, Screened* out);

// Confirms a screened candidate on every fit window (refined from its screening optimum,
// with covariance), evaluates it on the held-out windows and scores it (quasi-BIC,
// held-out gain, identifiability). One thread, as ScreenEffect.
void ConfirmEffect(const Screened& s, int round, const SelectionState& current, const Dataset& d,
                   Tried* out);

// The record of a candidate that screening left out: not confirmed, never accepted.
EffectTrial ScreenedOut(const Screened& s, int round, int rank, int ranked);

}  // namespace kincal::analysis
