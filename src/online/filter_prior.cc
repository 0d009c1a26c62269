#include "kincal/online/filter_prior.h"

#include <algorithm>
#include <cmath>

#include "kincal/plan/planner.h"
#include "kincal/sim/scenario.h"

namespace kincal {

FilterPrior GuessedPrior(const System& sys, const std::map<std::string, double>& guess,
                         double sigma_fraction, const std::map<std::string, double>& fixed,
                         const std::string& where) {
  const int np = sys.num_params();
  // The guess names only parameters of the model (validated by the caller): an error is a bug.
  FilterPrior p{ParamsFrom(sys, guess, where).value(), StateMat::Zero(np, np)};
  for (int i = 0; i < np; ++i) {
    const double s = sigma_fraction * std::max(std::abs(p.mean[i]),
                                               sys.params()[static_cast<size_t>(i)].default_sigma);
    p.covariance(i, i) = s * s;
  }
  HoldFixed(sys, fixed, &p.mean, &p.covariance);
  return p;
}

void HoldFixed(const System& sys, const std::map<std::string, double>& fixed, VecN<kMaxState>* mean,
               StateMat* covariance) {
  for (const auto& [name, v] : fixed) {
    const int i = sys.model().ParamIndex(name);  // validated with the config
    if (i < 0) continue;
    (*mean)[i] = v;
    covariance->row(i).setZero();
    covariance->col(i).setZero();
    const double s = kHeldSigmaFraction * sys.params()[static_cast<size_t>(i)].default_sigma;
    (*covariance)(i, i) = s * s;
  }
}

int ResumeFrom(const System& sys, const Checkpoint& ck, FilterPrior* prior) {
  const auto held = [&ck](const std::string& name) {
    return std::find(ck.held.begin(), ck.held.end(), name) != ck.held.end();
  };
  int matched = 0;
  for (size_t i = 0; i < ck.names.size(); ++i) {
    const int a = sys.ParamIndex(ck.names[i]);
    if (a < 0) continue;
    ++matched;
    prior->mean[a] = ck.values[i];
    // Held in the earlier run: its value, with this run's prior spread (zero would freeze
    // it; this run's robot.fixed holds it again when it is still held).
    if (held(ck.names[i])) continue;
    for (size_t k = 0; k < ck.names.size(); ++k) {
      const int b = sys.ParamIndex(ck.names[k]);
      if (b >= 0 && !held(ck.names[k])) {
        prior->covariance(a, b) = ck.covariance(static_cast<int>(i), static_cast<int>(k));
      }
    }
  }
  return matched;
}

}  // namespace kincal
