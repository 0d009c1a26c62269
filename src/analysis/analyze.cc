// kincal analyze: the stages in order. Windows (windows.cc), the baseline fit
// (baseline_fit.cc), regressors and the command lag (regressors.cc), the evaluation and
// residual tests (evaluation.cc), the diagnosis (diagnosis.cc) and effect selection
// (selection.cc).
#include "kincal/analysis/analyze.h"

#include <algorithm>
#include <map>
#include <sstream>

#include "analysis/baseline_fit.h"
#include "analysis/evaluation.h"
#include "analysis/parallel.h"
#include "analysis/regressors.h"
#include "analysis/runs.h"
#include "analysis/selection.h"
#include "analysis/units_check.h"
#include "analysis/windows.h"
#include "kincal/system.h"

namespace kincal {

namespace {

// The model must beat the better command-blind guess by this factor to explain the motion.
constexpr double kExplainsFraction = 0.8;
// Guesses closer than this many pose sigmas leave nothing to judge by, unless the commands
// asked for motion in at least this fraction of the held-out windows (then a model that
// does no better than standing still has missed what the commands did).
constexpr double kJudgeableSigmas = 5.0;
constexpr double kCommandedFraction = 0.5;

// The fraction of held-out windows that start with a non-zero command.
double CommandedFraction(const analysis::Dataset& d) {
  int commanded = 0, n = 0;
  for (const auto& w : d.eval) {
    const double ts = d.t[static_cast<size_t>(w.start)];
    if (!d.HeldOutAt(ts)) continue;
    const auto& u = d.rec->controls.At(ts);
    commanded += std::any_of(u.begin(), u.begin() + d.rec->controls.num_channels(),
                             [](double v) { return v != 0.0; });
    ++n;
  }
  return n > 0 ? static_cast<double>(commanded) / n : 0.0;
}

GoodnessOfFit Judge(const analysis::Dataset& d, double model_m) {
  GoodnessOfFit g;
  g.model_m = model_m;
  analysis::NaiveHeldOut(d, &g.standstill_m, &g.constant_velocity_m);
  const double guess = std::min(g.standstill_m, g.constant_velocity_m);
  g.judged = guess > kJudgeableSigmas * d.sigma[0] || CommandedFraction(d) >= kCommandedFraction;
  g.explains = !g.judged || model_m < kExplainsFraction * guess;
  std::ostringstream m;
  m.precision(3);
  if (!g.judged) {
    m << "the robot was hardly commanded and hardly moved over a horizon (" << guess
      << " m): the fit cannot be told from a guess that ignores the commands";
  } else if (!g.explains) {
    m << "the model explains nothing: its held-out error (" << model_m
      << " m at the horizon) is no better than "
      << (g.standstill_m <= g.constant_velocity_m ? "standing still (" : "constant velocity (")
      << guess << " m); check that the controls drive this robot and that the poses are its";
  } else {
    m << "the model predicts " << guess / std::max(model_m, 1e-12)
      << "x better than a guess that ignores the commands";
  }
  g.verdict = m.str();
  return g;
}

}  // namespace

bool AnalyzeOptions::IsValid(std::string* error) const {
  if (!(fit_fraction > 0.05 && fit_fraction < 0.95)) {
    *error = "--fit-fraction must be in (0.05, 0.95)";
    return false;
  }
  if (!(horizon_s > 0.0)) {
    *error = "--horizon must be > 0 s";
    return false;
  }
  if (effects_mode != "auto" && effects_mode != "none" && effects_mode != "list") {
    *error = "--effects must be auto, none or a list of effect names";
    return false;
  }
  for (const auto& [name, v] : fixed) {
    if (!std::isfinite(v)) {
      *error = "--fix " + name + ": the value must be finite";
      return false;
    }
  }
  if (pose_sigma && !((pose_sigma->array() > 0.0).all())) {
    *error = "pose sigmas must be > 0";
    return false;
  }
  if (max_effects < 0) {
    *error = "--max-effects must be >= 0";
    return false;
  }
  if (num_threads < 1) {
    *error = "--threads must be >= 1";
    return false;
  }
  if (screen_stride < 1 || confirm_candidates < 0) {
    *error = "screen_stride >= 1 and confirm_candidates >= 0 expected";
    return false;
  }
  if (max_fit_windows < 10 || max_eval_windows < 10 || poses_per_window < 1) {
    *error = "max_fit_windows, max_eval_windows >= 10, poses_per_window >= 1 expected";
    return false;
  }
  return true;
}

namespace {

using analysis::Dataset;
using analysis::Evaluation;
using analysis::Fit;
using analysis::SelectionState;
using analysis::Tried;

// Progress of the selection, for the progress callback: 0.3 at the start of the first
// round, 0.9 after the last round.
double SelectionProgress(int round, int max_rounds) { return 0.3 + 0.6 * (round - 1) / max_rounds; }

// The best candidate: supported by the criterion and improving the held-out error most.
Tried* Winner(std::vector<Tried>* tried, double min_gain) {
  Tried* winner = nullptr;
  for (auto& t : *tried) {
    if (!t.ok || t.trial.delta_bic >= 0.0 || t.trial.combined_gain < min_gain) continue;
    if (winner == nullptr || t.trial.combined_gain > winner->trial.combined_gain) winner = &t;
  }
  return winner;
}

// One round: every candidate not yet accepted screened (in parallel), the best
// confirm_candidates of them by screening cost confirmed (in parallel), the rest recorded
// in *screened_out; *warm receives each candidate's own parameters. Results are in
// candidate order whatever the thread count.
std::vector<Tried> RunRound(int round, const std::vector<std::string>& candidates,
                            const std::vector<std::string>& accepted, const SelectionState& current,
                            const Dataset& d, const std::shared_ptr<const KinematicModel>& model,
                            double command_lag, const AnalyzeOptions& o,
                            std::vector<EffectTrial>* screened_out,
                            std::map<std::string, Eigen::VectorXd>* warm) {
  const Eigen::Index old_np = current.fit.p.size();
  std::vector<std::string> todo;
  for (const auto& c : candidates) {
    const bool repeats = std::any_of(accepted.begin(), accepted.end(),
                                     [&](const std::string& a) { return analysis::Repeats(c, a); });
    if (!repeats) todo.push_back(c);
  }
  // Parallel over candidates, each solve on one thread: the result does not depend on
  // the thread count.
  std::vector<analysis::Screened> screened(todo.size());
  std::vector<char> made(todo.size(), 0);
  analysis::ParallelFor(todo.size(), o.num_threads, [&](size_t i) {
    made[i] = analysis::ScreenEffect(todo[i], current, d, model, command_lag,
                                     o.effects_mode == "list", &screened[i]);
  });
  // Rank by screening cost (ties by candidate order); confirm the leading ones.
  std::vector<size_t> order;
  for (size_t i = 0; i < todo.size(); ++i) {
    if (made[i]) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const auto& fa = screened[a].fit;
    const auto& fb = screened[b].fit;
    if (fa.ok != fb.ok) return fa.ok;
    return fa.ok && fa.cost < fb.cost;
  });
  const size_t confirm = o.confirm_candidates == 0
                             ? order.size()
                             : std::min(order.size(), static_cast<size_t>(o.confirm_candidates));
  std::vector<size_t> confirm_idx;
  for (size_t r = 0; r < order.size(); ++r) {
    if (r < confirm && screened[order[r]].ok) {
      confirm_idx.push_back(order[r]);
    } else {
      screened_out->push_back(analysis::ScreenedOut(
          screened[order[r]], round, static_cast<int>(r) + 1, static_cast<int>(order.size())));
    }
  }
  std::sort(confirm_idx.begin(), confirm_idx.end());  // back to candidate order
  std::vector<Tried> tried(confirm_idx.size());
  analysis::ParallelFor(confirm_idx.size(), o.num_threads, [&](size_t k) {
    analysis::ConfirmEffect(screened[confirm_idx[k]], round, current, d, &tried[k]);
  });
  // Each candidate's own parameters, for the next round's warm start.
  for (const auto& sc : screened) {
    if (sc.ok) (*warm)[sc.spec] = sc.fit.p.tail(sc.fit.p.size() - old_np);
  }
  std::vector<Tried> out;
  for (auto& t : tried) {
    if (!t.fit.ok) continue;
    (*warm)[t.trial.name] = t.fit.p.tail(t.fit.p.size() - old_np);
    out.push_back(std::move(t));
  }
  return out;
}

// Run by run, and dead reckoning over the held-out part, before and after.
void JudgeRuns(const Dataset& d, const System& bare, const SelectionState& before,
               const System& final_sys, const SelectionState& after, AnalyzeResult* res) {
  res->runs =
      analysis::PerRun(d, before.eval, after.eval, bare, before.fit.p, final_sys, after.fit.p);
  res->heldout_dr_before = analysis::HeldOutDeadReckoning(bare, before.fit.p, d);
  res->heldout_dr_after = analysis::HeldOutDeadReckoning(final_sys, after.fit.p, d);
}

// An effect from its spec (name[channels]:params) on `model`.
Status EffectFrom(const std::string& spec_text, const KinematicModel& model,
                  std::unique_ptr<Effect>* e) {
  EffectSpec spec;
  Status st = ParseEffectSpec(spec_text, &spec);
  if (st.ok()) st = MakeEffect(spec, model, e);
  return st;
}

// The model and the effects already in it (o.base_effects); an error names the spec. A
// user's effect list (--effects) is checked here too, before the selection screens it.
Status MakeBaseModel(const AnalyzeOptions& o, std::shared_ptr<const KinematicModel>* model,
                     std::vector<std::shared_ptr<const Effect>>* base_effects) {
  if (const Status s = MakeModel(o.model, model); !s.ok()) return s;
  for (const auto& spec_text : o.base_effects) {
    std::unique_ptr<Effect> e;
    if (const Status st = EffectFrom(spec_text, **model, &e); !st.ok())
      return Status::Error("base effects: " + st.message());
    base_effects->push_back(std::move(e));
  }
  if (const Status st = System::CheckCombination(**model, *base_effects, {}); !st.ok()) {
    return Status::Error("base effects: " + st.message());
  }
  if (o.effects_mode != "list") return Status();
  for (const auto& spec_text : o.effects) {
    std::unique_ptr<Effect> e;
    if (const Status st = EffectFrom(spec_text, **model, &e); !st.ok())
      return Status::Error("--effects: " + st.message());
  }
  return Status();
}

// The rounds of the selection from *current (the baseline): each screens every candidate on
// top of what was accepted, then confirms the leading ones on all windows; the winner of a
// round becomes *current. Returns the effects in the model at the end (base ones first).
std::vector<std::string> SelectEffects(const Dataset& d,
                                       const std::shared_ptr<const KinematicModel>& model,
                                       double command_lag, const AnalyzeOptions& o,
                                       SelectionState* current, AnalyzeResult* res) {
  std::vector<std::string> accepted = o.base_effects;
  const auto candidates = analysis::Candidates(*model, o);
  for (int round = 1; round <= o.max_effects && !candidates.empty(); ++round) {
    if (o.progress)
      o.progress(SelectionProgress(round, o.max_effects), "round " + std::to_string(round));
    std::map<std::string, Eigen::VectorXd> warm;
    std::vector<Tried> tried = RunRound(round, candidates, accepted, *current, d, model,
                                        command_lag, o, &res->trials, &warm);
    for (auto& [spec, p] : warm) current->warm[spec] = std::move(p);
    Tried* winner = Winner(&tried, o.min_gain);
    for (auto& t : tried) {
      if (&t == winner) t.trial.accepted = true;
      res->trials.push_back(t.trial);
    }
    if (winner == nullptr) break;
    accepted.push_back(winner->trial.name);
    current->effects = winner->effects;
    current->fit = winner->fit;
    current->eval = winner->eval;
    current->diagnosis = Diagnose(current->eval.points, d.features, d.horizon);
    res->residual_steps.push_back({"+" + winner->trial.name, current->eval.points});
  }
  return accepted;
}

// What the analysis starts from: the bare model, its start point with the held
// parameters, and the recording cut into windows.
struct Start {
  std::shared_ptr<const KinematicModel> model;
  std::vector<std::shared_ptr<const Effect>> base_effects;
  Eigen::VectorXd p0;
  Dataset d;
};

StatusOr<Start> MakeStart(const Recording& rec, const AnalyzeOptions& o,
                          std::vector<std::string>* warnings) {
  std::string error;
  if (!o.IsValid(&error)) return Status::Error(error);
  Start s;
  if (const Status st = MakeBaseModel(o, &s.model, &s.base_effects); !st.ok()) return st;
  const System bare(s.model, s.base_effects);
  StatusOr<Eigen::VectorXd> p0 = analysis::InitialParams(bare, o.init);  // unknown names first
  if (!p0.ok()) return p0.status();
  s.p0 = std::move(p0).value();
  StatusOr<std::vector<int>> fixed = analysis::FixParams(bare, o.fixed, &s.p0);
  if (!fixed.ok()) return fixed.status();
  StatusOr<Dataset> d = analysis::Prepare(rec, o, warnings);
  if (!d.ok()) return d.status();
  s.d = std::move(d).value();
  s.d.limits.fixed = std::move(fixed).value();
  return s;
}

}  // namespace

StatusOr<AnalyzeResult> Analyze(const Recording& rec, const AnalyzeOptions& o) {
  AnalyzeResult res;
  res.model = o.model;
  res.source = rec.source;
  res.stats = rec.stats;
  res.warnings = rec.warnings;
  res.horizon_s = o.horizon_s;
  auto progress = [&](double f, const std::string& s) {
    if (o.progress) o.progress(f, s);
  };
  StatusOr<Start> start = MakeStart(rec, o, &res.warnings);
  if (!start.ok()) return start.status();
  const std::shared_ptr<const KinematicModel> model = start->model;
  const System bare(model, start->base_effects);  // the model as it stands (bare unless base)
  Dataset& d = start->d;
  res.pose_sigma = d.sigma;
  res.pose_sigma_estimated = !o.pose_sigma.has_value();
  res.t_begin_s = std::max(d.t.front(), d.t_ctrl0);
  res.t_split_s = d.t_split;
  res.t_end_s = d.t.back();

  // 1. Baseline.
  progress(0.02, "baseline");
  FitReport base_report;
  SelectionState current;
  StatusOr<Fit> base_fit = analysis::FitBaseline(bare, d, start->p0, o, &base_report);
  if (!base_fit.ok()) return base_fit.status();
  current.fit = std::move(base_fit).value();
  analysis::ComputeFeatures(&d, bare, current.fit.p);
  const double command_lag = analysis::EstimateCommandLag(d, bare, current.fit.p);
  current.eval = analysis::Evaluate(bare, current.fit.p, d);
  const int fit_windows = static_cast<int>(d.fit_windows.size());
  res.before = analysis::MakeReport(bare, current.fit, current.eval, o.base_effects, fit_windows);
  res.before.unique = base_report.unique;
  res.before.uniqueness = base_report.uniqueness;
  if (!res.before.unobservable.empty()) {
    std::string m = rec.source + ": ";
    for (const auto& s : res.before.unobservable) m += s + ". ";
    return Status::Error(m);
  }
  res.diagnosis_before = Diagnose(current.eval.points, d.features, d.horizon);
  res.tests_before = analysis::TestResiduals(current.eval, o.horizon_s);
  res.residual_steps.push_back({"before", current.eval.points});
  current.diagnosis = res.diagnosis_before;
  current.effects = start->base_effects;
  const SelectionState baseline = current;

  // 2. Selection: each round screens every candidate on top of what was accepted, then
  // confirms the leading ones on all windows.
  const std::vector<std::string> accepted = SelectEffects(d, model, command_lag, o, &current, &res);
  progress(0.95, "report");
  const System final_sys(model, current.effects);
  res.after = analysis::MakeReport(final_sys, current.fit, current.eval, accepted, fit_windows);
  res.diagnosis_after = current.diagnosis;
  res.tests_after = analysis::TestResiduals(current.eval, o.horizon_s);
  for (const std::string& w : analysis::UnitWarnings(*model, current.fit.p))
    res.warnings.push_back(rec.source + ": " + w);
  res.goodness = Judge(d, res.after.heldout.pos_rms_m);
  JudgeRuns(d, bare, baseline, final_sys, current, &res);
  if (res.goodness.judged && !res.goodness.explains) {
    res.warnings.push_back(res.goodness.verdict);
    for (FitReport* f : {&res.before, &res.after}) {
      f->unique = false;
      f->uniqueness = res.goodness.verdict;
    }
  }
  progress(1.0, "done");
  return res;
}

}  // namespace kincal
