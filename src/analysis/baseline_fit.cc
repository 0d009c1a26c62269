#include "analysis/baseline_fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include "analysis/parallel.h"

namespace kincal::analysis {

Fit RunFit(const System& sys, const ControlSignal& u, const std::vector<PoseMeasurement>& meas,
           const Eigen::VectorXd& p0, const FitLimits& limits, bool covariance, int threads,
           int max_iterations) {
  BatchOptions o;
  o.fixed = limits.fixed;
  o.run_starts = limits.run_starts;
  o.compute_covariance = false;
  o.profiled_covariance = covariance;
  o.max_iterations = max_iterations;
  o.num_threads = threads;
  Fit f;
  f.fixed = limits.fixed;
  const BatchResult r = FitBatch(sys, u, meas, p0, o);
  if (!r.status.ok()) return f;  // not ok: the caller tries another start or candidate
  f.p = r.params;
  f.cost = 2.0 * r.final_cost;
  f.ok = f.p.allFinite() && std::isfinite(f.cost);
  f.cov_robust = r.robust_covariance;
  f.cov_model = r.profiled_covariance;
  f.info = r.information;
  f.n_eff = r.effective_residuals;
  return f;
}

std::vector<ParamEstimate> Estimates(const System& sys, const Fit& f, int from, int to) {
  std::vector<ParamEstimate> out;
  for (int i = from; i < to; ++i) {
    const auto& pi = sys.params()[static_cast<size_t>(i)];
    ParamEstimate e{pi.name, pi.unit, f.p[i], NAN, NAN};
    e.held = std::find(f.fixed.begin(), f.fixed.end(), i) != f.fixed.end();
    if (f.cov_robust.rows() == f.p.size()) e.sigma = std::sqrt(std::max(0.0, f.cov_robust(i, i)));
    if (f.cov_model.rows() == f.p.size())
      e.sigma_model = std::sqrt(std::max(0.0, f.cov_model(i, i)));
    out.push_back(e);
  }
  return out;
}

// Parameters the information matrix cannot pin down.
std::vector<std::string> Unobservable(const System& sys, const Fit& f) {
  std::vector<std::string> msgs;
  const int np = static_cast<int>(f.p.size());
  if (f.info.rows() != np) return msgs;
  // Scale to relative units so that the test is unit free.
  Eigen::VectorXd s(np);
  for (int i = 0; i < np; ++i) {
    s[i] = std::max(std::abs(f.p[i]), sys.params()[static_cast<size_t>(i)].default_sigma);
  }
  Eigen::MatrixXd I = s.asDiagonal() * f.info * s.asDiagonal();
  const double largest = std::max(I.diagonal().maxCoeff(), 1.0);
  for (int i : f.fixed) {  // held: determined by the user, not by the data
    I.row(i).setZero();
    I.col(i).setZero();
    I(i, i) = largest;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(I);
  const double top = std::max(es.eigenvalues().maxCoeff(), 1e-300);
  for (int k = 0; k < np; ++k) {
    if (es.eigenvalues()[k] > 1e-9 * top && es.eigenvalues()[k] > 1e-6) continue;
    const Eigen::VectorXd v = es.eigenvectors().col(k);
    int imax = 0;
    v.cwiseAbs().maxCoeff(&imax);
    const auto& pi = sys.params()[static_cast<size_t>(imax)];
    std::string msg = "parameter '" + pi.name + "' is not identifiable from this recording";
    std::string others;
    for (int i = 0; i < np; ++i) {
      if (i != imax && std::abs(v[i]) > 0.3 * std::abs(v[imax]))
        others += (others.empty() ? "" : ", ") + sys.params()[static_cast<size_t>(i)].name;
    }
    if (!others.empty()) {
      msg += " (it trades off against " + others + "): hold one at a known value (--fix " +
             pi.name + "=VALUE)";
      if (!pi.excitation.empty()) msg += " or excite it with " + pi.excitation;
    } else if (!pi.excitation.empty()) {
      msg += "; excite it with " + pi.excitation;
    }
    msgs.push_back(msg);
  }
  return msgs;
}

StatusOr<Eigen::VectorXd> InitialParams(const System& sys,
                                        const std::map<std::string, double>& init) {
  Eigen::VectorXd p(sys.num_params());
  for (int i = 0; i < sys.num_params(); ++i)
    p[i] = sys.params()[static_cast<size_t>(i)].default_value;
  for (const auto& [name, v] : init) {
    const int i = sys.ParamIndex(name);
    if (i < 0) {
      return Status::Error("--init: model '" + std::string(sys.model().name()) +
                           "' has no parameter '" + name +
                           "' (its parameters: " + ParamNames(sys.params()) + ")");
    }
    const std::string problem = ParamValueProblem(sys.params()[static_cast<size_t>(i)], v);
    if (!problem.empty()) return Status::Error("--init: " + problem);
    p[i] = v;
  }
  return p;
}

StatusOr<std::vector<int>> FixParams(const System& sys, const std::map<std::string, double>& fixed,
                                     Eigen::VectorXd* p0) {
  const KinematicModel& model = sys.model();
  const std::string known = ParamNames(model.params());
  std::vector<int> idx;
  for (const auto& [name, v] : fixed) {
    const int i = model.ParamIndex(name);
    if (i < 0) {
      return Status::Error("--fix: model '" + std::string(model.name()) + "' has no parameter '" +
                           name + "' (its parameters: " + known + ")");
    }
    const std::string problem = ParamValueProblem(model.params()[static_cast<size_t>(i)], v);
    if (!problem.empty()) return Status::Error("--fix: " + problem);
    (*p0)[i] = v;
    idx.push_back(i);
  }
  if (!idx.empty() && static_cast<int>(idx.size()) == model.num_params()) {
    return Status::Error("--fix: every parameter of model '" + std::string(model.name()) +
                         "' is fixed (" + known + "): nothing is left to calibrate");
  }
  std::sort(idx.begin(), idx.end());
  return idx;
}

std::vector<std::string> WeaklyDetermined(const System& sys, const Fit& f) {
  std::vector<std::string> out;
  const int np = static_cast<int>(f.p.size());
  if (f.cov_robust.rows() != np) return out;
  auto held = [&](int i) { return std::find(f.fixed.begin(), f.fixed.end(), i) != f.fixed.end(); };
  auto sigma = [&](int i) { return std::sqrt(std::max(f.cov_robust(i, i), 0.0)); };
  auto name = [&](int i) { return sys.params()[static_cast<size_t>(i)].name; };
  for (int i = 0; i < np; ++i) {
    if (held(i)) continue;
    const auto& pi = sys.params()[static_cast<size_t>(i)];
    std::string partners;
    for (int j = 0; j < np; ++j) {
      if (j == i || held(j) || sigma(i) <= 0.0 || sigma(j) <= 0.0) continue;
      const double r = f.cov_robust(i, j) / (sigma(i) * sigma(j));
      if (std::abs(r) > 0.98) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s (correlation %+.3f)", name(j).c_str(), r);
        partners += (partners.empty() ? "" : ", ") + std::string(buf);
      }
    }
    const bool loose = pi.default_value != 0.0 && sigma(i) > 0.5 * std::abs(f.p[i]);
    if (partners.empty() && !loose) continue;
    std::string m = "'" + pi.name + "' is weakly determined";
    char buf[96];
    std::snprintf(buf, sizeof buf, " (%.4g +- %.2g %s)", f.p[i], sigma(i), pi.unit.c_str());
    m += buf;
    if (!partners.empty()) m += ": it trades off against " + partners;
    m += "; to separate them, hold one at a known value (--fix " + pi.name + "=VALUE)";
    if (!pi.excitation.empty()) m += " or drive " + pi.excitation;
    out.push_back(m);
  }
  return out;
}

namespace {

// The starts of the multi-start: the guess, each parameter scaled (or shifted by its
// default sigma when it is not a scale) by 0.2, 0.5, 2 and 5, and six random mixes.
std::vector<Eigen::VectorXd> BaselineStarts(const System& sys, const Eigen::VectorXd& p0,
                                            const std::vector<int>& fixed, uint64_t seed) {
  const int np = sys.num_params();
  std::vector<Eigen::VectorXd> starts = {p0};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto is_scale = [&](int i) {
    return sys.params()[static_cast<size_t>(i)].default_value != 0.0 && p0[i] != 0.0;
  };
  auto held = [&](int i) { return std::find(fixed.begin(), fixed.end(), i) != fixed.end(); };
  for (int i = 0; i < np; ++i) {
    if (held(i)) continue;
    for (double f : {0.2, 0.5, 2.0, 5.0}) {
      Eigen::VectorXd s = p0;
      if (is_scale(i)) {
        s[i] *= f;
      } else {
        s[i] += (f < 1.0 ? -1.0 : 1.0) * (f == 0.5 || f == 2.0 ? 1.0 : 3.0) *
                sys.params()[static_cast<size_t>(i)].default_sigma;
      }
      starts.push_back(s);
    }
  }
  for (int r = 0; r < 6; ++r) {
    Eigen::VectorXd s = p0;
    for (int i = 0; i < np; ++i) {
      if (held(i)) continue;
      if (is_scale(i)) {
        s[i] *= std::exp(std::log(5.0) * unit(rng));
      } else {
        s[i] += 2.0 * sys.params()[static_cast<size_t>(i)].default_sigma * gauss(rng);
      }
    }
    starts.push_back(s);
  }
  return starts;
}

// The best few distinct optima of the short-window fits (sorted by cost) worth refining.
std::vector<const Fit*> DistinctSeeds(const std::vector<Fit>& stage1) {
  std::vector<const Fit*> seeds;
  for (size_t k = 0; k < stage1.size() && seeds.size() < 3; ++k) {
    bool distinct = true;
    for (const Fit* r : seeds) {
      if (((stage1[k].p - r->p).array().abs() <= 1e-3 * (r->p.array().abs() + 1e-6)).all())
        distinct = false;
    }
    if (!distinct && k > 0) continue;
    if (stage1[k].cost > 1.5 * stage1[0].cost + 10.0) break;
    seeds.push_back(&stage1[k]);
  }
  return seeds;
}

// Says in *report when another refined optimum fits as well as the best but differs from it
// by more than 5 sigma in a parameter.
void CheckUnique(const System& sys, const std::vector<Fit>& refined, FitReport* report) {
  const Fit& best = refined.front();
  const int np = sys.num_params();
  report->unique = true;
  for (size_t k = 1; k < refined.size(); ++k) {
    const Fit& alt = refined[k];
    if (alt.cost > best.cost * 1.01 + 2.0) continue;  // clearly worse
    bool differs = false;
    for (int i = 0; i < np && best.cov_robust.rows() == np; ++i) {
      if (std::abs(alt.p[i] - best.p[i]) > 5.0 * std::sqrt(std::max(best.cov_robust(i, i), 1e-300)))
        differs = true;
    }
    if (differs) {
      report->unique = false;
      std::ostringstream m;
      m << "another optimum fits as well (cost " << alt.cost << " vs " << best.cost << "):";
      for (int i = 0; i < np; ++i)
        m << " " << sys.params()[static_cast<size_t>(i)].name << "=" << alt.p[i];
      report->uniqueness = m.str();
    }
  }
}

// The fits that succeeded, cheapest first.
std::vector<Fit> OkByCost(std::vector<Fit> fits) {
  std::vector<Fit> ok;
  for (auto& f : fits) {
    if (f.ok) ok.push_back(std::move(f));
  }
  std::sort(ok.begin(), ok.end(), [](const Fit& a, const Fit& b) { return a.cost < b.cost; });
  return ok;
}

}  // namespace

// Multi-start, staged fit of the bare model: short windows from many starts, then the best
// refined on full windows. Reports when distinct optima fit equally well.
StatusOr<Fit> FitBaseline(const System& sys, const Dataset& d, const Eigen::VectorXd& p0,
                          const AnalyzeOptions& o, FitReport* report) {
  const auto& u = d.rec->controls;
  const std::vector<Eigen::VectorXd> starts = BaselineStarts(sys, p0, d.limits.fixed, o.seed);
  // The starts in parallel, each solve on one thread: the result does not depend on the
  // thread count.
  if (o.progress) o.progress(0.05, "baseline: multi-start");
  std::vector<Fit> fits(starts.size());
  ParallelFor(starts.size(), o.num_threads, [&](size_t k) {
    fits[k] = RunFit(sys, u, d.short_meas, starts[k], d.limits, false, 1, 40);
  });
  const std::vector<Fit> stage1 = OkByCost(std::move(fits));
  if (stage1.empty())
    return Status::Error(d.rec->source +
                         ": the baseline fit failed from every start: check that the controls "
                         "drive the model (units, column order)");
  // Refine the best few distinct optima on the full windows (in parallel).
  const std::vector<const Fit*> seeds = DistinctSeeds(stage1);
  std::vector<Fit> tops(seeds.size());
  ParallelFor(seeds.size(), o.num_threads, [&](size_t k) {
    tops[k] = RunFit(sys, u, d.fit_meas, seeds[k]->p, d.limits, true, 1);
  });
  const std::vector<Fit> refined = OkByCost(std::move(tops));
  if (refined.empty()) return Status::Error(d.rec->source + ": the baseline refinement failed");
  CheckUnique(sys, refined, report);
  return refined.front();
}

}  // namespace kincal::analysis
