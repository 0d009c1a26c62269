// Where the online estimator starts: the parameters and their covariance, from a guess, a
// checkpoint resumed, and the parameters held at a known value.
#pragma once

#include <map>
#include <string>

#include "kincal/io/checkpoint.h"
#include "kincal/system.h"
#include "kincal/types.h"

namespace kincal {

// What the stage starts from: parameters and their covariance (the configured guess, or a
// checkpoint resumed).
struct FilterPrior {
  VecN<kMaxState> mean;
  StateMat covariance;
};
// A guess (by parameter name; the model's defaults for the rest) with sigma_fraction of
// each value (or of the parameter's default sigma, whichever is larger) as its sigma, and
// the `fixed` parameters held (HoldFixed). The names are validated by the caller (a name
// the model lacks is a bug); `where` names the guess in that message.
FilterPrior GuessedPrior(const System& sys, const std::map<std::string, double>& guess,
                         double sigma_fraction, const std::map<std::string, double>& fixed,
                         const std::string& where);
// Holds robot.fixed: each named parameter at its value with a negligible sigma
// (kHeldSigmaFraction of its default sigma) and no correlation, so that the filter does not
// move it.
void HoldFixed(const System& sys, const std::map<std::string, double>& fixed, VecN<kMaxState>* mean,
               StateMat* covariance);

// Replaces the prior's parameters that a checkpoint has (matched by name; the others keep
// the configured prior). Returns how many matched.
int ResumeFrom(const System& sys, const Checkpoint& ck, FilterPrior* prior);

}  // namespace kincal
