#include "analysis/selection.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "kincal/check.h"

namespace kincal::analysis {
namespace {

// A time-varying effect (a lag) also starts at the command lag when that lag exceeds this.
constexpr double kMinLagForStartS = 0.05;
// Extra starts for a single new parameter: its default +- this many default sigmas.
constexpr double kStartSpreadSigmas = 2.0;
// The best start is refined with the covariance, for at most this many iterations.
constexpr int kRefineIterations = 20;

// Starting points for one candidate's fit; `warm` holds its own parameters from the last
// round (empty the first time: then the spread starts explore around the default).
std::vector<Eigen::VectorXd> Starts(const System& sys, const Effect& eff, const Eigen::VectorXd& p,
                                    double command_lag, const Eigen::VectorXd* warm) {
  const int old_np = static_cast<int>(p.size());
  const int np = sys.num_params();
  Eigen::VectorXd s0(np);
  s0.head(old_np) = p;
  for (int i = old_np; i < np; ++i) s0[i] = sys.params()[static_cast<size_t>(i)].default_value;
  std::vector<Eigen::VectorXd> starts = {s0};
  if (warm != nullptr && warm->size() == np - old_np) {
    starts.front().tail(np - old_np) = *warm;  // the last round explored the defaults
  }
  const bool timing = eff.stage() == EffectStage::kControlTiming;
  if (np - old_np == 1 && warm == nullptr &&
      (timing || (eff.time_varying() && std::abs(command_lag) > kMinLagForStartS))) {
    // Timing: start at the lag the cross-correlation found (a delay or a lag's tau).
    Eigen::VectorXd s = s0;
    s[np - 1] = timing ? command_lag : std::abs(command_lag);
    starts.push_back(s);
  }
  if (np - old_np == 1 && warm == nullptr) {
    for (double k : {-kStartSpreadSigmas, kStartSpreadSigmas}) {
      Eigen::VectorXd s = s0;
      s[np - 1] += k * sys.params()[static_cast<size_t>(np - 1)].default_sigma;
      starts.push_back(s);
    }
  }
  return starts;
}

}  // namespace

// Candidate effect specs for a model.
std::vector<std::string> Candidates(const KinematicModel& m, const AnalyzeOptions& o) {
  if (o.effects_mode == "none") return {};
  if (o.effects_mode == "list") return o.effects;
  std::vector<std::string> out;
  for (const auto& name : EffectRegistry::Instance().Names()) {
    auto e = EffectRegistry::Instance().Create(name);
    if (!e->AppliesTo(m)) continue;
    std::string error;
    if (!e->Bind(m, {}, &error)) continue;
    out.push_back(name);
    // Channel-wise effects: also one candidate per channel.
    auto probe = EffectRegistry::Instance().Create(name);
    if (m.num_controls() > 1 && probe->Bind(m, {m.controls()[0].name}, &error)) {
      for (const auto& c : m.controls()) out.push_back(name + "[" + c.name + "]");
    }
  }
  return out;
}

bool Repeats(const std::string& candidate, const std::string& accepted) {
  EffectSpec c, a;
  if (!ParseEffectSpec(candidate, &c).ok() || !ParseEffectSpec(accepted, &a).ok()) return false;
  if (c.name != a.name) return false;
  if (c.channels.empty() || a.channels.empty()) return true;  // all channels
  for (const auto& ch : c.channels) {
    if (std::find(a.channels.begin(), a.channels.end(), ch) != a.channels.end()) return true;
  }
  return false;
}

FitReport MakeReport(const System& sys, const Fit& f, const Evaluation& e,
                     const std::vector<std::string>& effects, int fit_windows) {
  FitReport r;
  r.effects = effects;
  r.params = Estimates(sys, f, 0, sys.num_params());
  if (f.cov_robust.rows() == f.p.size()) r.covariance = f.cov_robust;
  r.fit = e.fit;
  r.heldout = e.held;
  r.cost = f.cost;
  r.fit_windows = fit_windows;
  r.unobservable = Unobservable(sys, f);
  r.weak = WeaklyDetermined(sys, f);
  for (int i : f.fixed) {
    std::ostringstream m;
    m.precision(10);
    m << sys.params()[static_cast<size_t>(i)].name << "=" << f.p[i];
    r.fixed.push_back(m.str());
  }
  return r;
}

bool ScreenEffect(const std::string& spec, const SelectionState& current, const Dataset& d,
                  const std::shared_ptr<const KinematicModel>& model, double command_lag,
                  bool user_list, Screened* out) {
  EffectSpec parsed;
  std::unique_ptr<Effect> made;
  Status status = ParseEffectSpec(spec, &parsed);
  if (status.ok()) status = MakeEffect(parsed, *model, &made);
  // A candidate that does not apply (a user's list was checked by Analyze before the
  // selection started: KINCAL_CHECK).
  if (!status.ok()) {
    KINCAL_CHECK(!user_list, status.message().c_str());
    return false;
  }
  const std::shared_ptr<const Effect> eff = std::move(made);
  std::vector<std::shared_ptr<const Effect>> effects = current.effects;
  effects.push_back(eff);
  if (!System::CheckCombination(*model, effects, {}).ok()) {
    return false;  // conflicts with an accepted effect (same parameters)
  }
  const System sys(model, effects);
  out->spec = spec;
  out->model = model;
  out->effects = effects;
  const auto warm = current.warm.find(spec);
  const Eigen::VectorXd* w = warm == current.warm.end() ? nullptr : &warm->second;
  for (const auto& s : Starts(sys, *eff, current.fit.p, command_lag, w)) {
    Fit f = RunFit(sys, d.rec->controls, d.screen_meas, s, d.limits, false, 1);
    if (f.ok && (!out->fit.ok || f.cost < out->fit.cost)) out->fit = std::move(f);
  }
  out->ok = out->fit.ok;
  return true;
}

void ConfirmEffect(const Screened& s, int round, const SelectionState& current, const Dataset& d,
                   Tried* out) {
  const System sys(s.model, s.effects);
  Tried& t = *out;
  t.trial.name = s.spec;
  t.trial.round = round;
  t.trial.signature_z = SignatureZ(s.effects.back()->signature(), current.diagnosis);
  t.effects = s.effects;
  const Fit best =
      RunFit(sys, d.rec->controls, d.fit_meas, s.fit.p, d.limits, true, 1, kRefineIterations);
  if (!best.ok) return;
  t.fit = best;
  t.eval = Evaluate(sys, best.p, d);
  const int old_np = static_cast<int>(current.fit.p.size());
  const int np = sys.num_params();
  const int k = np - old_np;
  // Quasi-BIC: residuals within a window are correlated, so the sample size is the
  // effective number of independent residuals (AR(1) design effect of the larger model,
  // never fewer than one per window).
  const double n_eff = std::max(static_cast<double>(d.fit_windows.size()), best.n_eff);
  const double cost = current.fit.cost;
  t.trial.delta_bic =
      n_eff * std::log(std::max(best.cost, 1e-300) / std::max(cost, 1e-300)) + k * std::log(n_eff);
  const ErrorStats& held = current.eval.held;
  t.trial.heldout_gain = 1.0 - t.eval.held.pos_rms_m / std::max(held.pos_rms_m, 1e-300);
  t.trial.combined_gain =
      1.0 - Combined(t.eval.held, d.sigma) / std::max(Combined(held, d.sigma), 1e-300);
  t.trial.params = Estimates(sys, best, old_np, np);
  const bool observable = Unobservable(sys, best).empty();
  std::ostringstream ev;
  ev.precision(3);
  ev << "signature z=" << t.trial.signature_z << "; fit cost " << (best.cost / cost - 1.0) * 100.0
     << " %, dBIC " << t.trial.delta_bic << "; held-out position RMS " << held.pos_rms_m << " -> "
     << t.eval.held.pos_rms_m << " m, heading RMS " << held.heading_rms_rad << " -> "
     << t.eval.held.heading_rms_rad << " rad";
  if (!observable) ev << "; not identifiable together with the model's parameters";
  t.trial.evidence = ev.str();
  t.ok = observable;
}

EffectTrial ScreenedOut(const Screened& s, int round, int rank, int ranked) {
  EffectTrial t;
  t.name = s.spec;
  t.round = round;
  std::ostringstream ev;
  ev << "screened out: its fit on the screening windows ranked " << rank << " of " << ranked
     << (s.ok ? "" : " (no start converged)") << "; not confirmed";
  t.evidence = ev.str();
  return t;
}

}  // namespace kincal::analysis
