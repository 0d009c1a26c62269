#include "kincal/plan/planner.h"

#include <Eigen/Dense>
#include <cmath>
#include <future>
#include <numeric>
#include <optional>
#include <sstream>
#include <utility>

#include "kincal/angles.h"
#include "kincal/text.h"
#include "plan/fleet.h"
#include "plan/greedy.h"
#include "plan/judged_design.h"
#include "plan/refine.h"
#include "plan/seeding.h"
#include "plan/shaping.h"
#include "plan/within_prior.h"

namespace kincal {
namespace {

using plan_internal::Values;

Eigen::VectorXd PriorSigma(const Eigen::MatrixXd& prior_cov) {
  return prior_cov.diagonal().cwiseSqrt();
}

// Parameter i's prior sigma set to `sigma`, uncorrelated with the others.
void SetSigmaAlone(int i, double sigma, Eigen::MatrixXd* prior_cov) {
  prior_cov->row(i).setZero();
  prior_cov->col(i).setZero();
  (*prior_cov)(i, i) = sigma * sigma;
}

}  // namespace

bool EveryRobotStaysIn(const System& sys, const Eigen::VectorXd& params,
                       const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                       const ControlSignal& u) {
  return plan_internal::FleetStaysInside(sys, params, prior_cov, ws, o, u,
                                         plan_internal::CornersInside);
}

namespace {

// The greedy plan, or the best continuous usual motion (one segment: the thesis's runs
// carry the robot back between runs) that keeps every robot within the prior inside
// (UsualMotions checked it), whichever ranks better.
void KeepTheBetter(const PlanOptions& o, const Eigen::VectorXd& prior_sigma,
                   const std::vector<Motion>& usual, Motion* plan) {
  double best = MotionRank(*plan, o, prior_sigma);
  const Motion* better = nullptr;
  for (const Motion& m : usual) {
    if (m.segment_starts_s.size() != 1 || !m.stays_in || !m.every_robot_stays_in) continue;
    const double rank = MotionRank(m, o, prior_sigma);
    if (rank < best) {
      best = rank;
      better = &m;
    }
  }
  if (better == nullptr) return;
  *plan = *better;
  plan->name = "plan: " + better->name;
}

// PlanOptions::IsValid by group: the timing, the control limits, the design.
bool ValidTiming(const PlanOptions& o, std::string* error) {
  std::ostringstream why;
  if (!(o.duration_s > 0.0 && o.duration_s <= kMaxPlanDurationS)) {
    why << "duration_s: in (0, " << kMaxPlanDurationS << "] s expected, not " << o.duration_s;
  } else if (!(o.control_rate_hz >= 1.0 && o.control_rate_hz <= kMaxPlanControlRateHz)) {
    why << "control_rate_hz: in [1, " << kMaxPlanControlRateHz << "] Hz expected, not "
        << o.control_rate_hz;
  } else if (!(o.segment_s >= 1.0 / o.control_rate_hz)) {
    why << "segment_s: " << o.segment_s << " s is shorter than one control period ("
        << 1.0 / o.control_rate_hz << " s at " << o.control_rate_hz << " Hz)";
  } else if (!(o.segment_s <= o.duration_s)) {
    why << "segment_s: " << o.segment_s << " s is longer than the plan (duration_s " << o.duration_s
        << " s)";
  }
  *error = why.str();
  return error->empty();
}

bool ValidLimits(const PlanOptions& o, const System& sys, std::string* error) {
  const size_t nc = static_cast<size_t>(sys.num_controls());
  if (o.max_abs.size() != nc) {
    *error = "a limit for every control of " + std::string(sys.model().name()) + " expected (";
    for (const auto& c : sys.model().controls()) *error += c.name + "=.. ";
    *error += "missing)";
    return false;
  }
  for (size_t c = 0; c < nc; ++c) {
    if (!(o.max_abs[c] > 0.0) || !std::isfinite(o.max_abs[c]) ||
        (c < o.max_accel.size() && !(o.max_accel[c] >= 0.0))) {
      *error = "limit of " + sys.model().controls()[c].name +
               ": a positive value (and an acceleration >= 0) expected";
      return false;
    }
  }
  return true;
}

bool ValidDesign(const PlanOptions& o, const System& sys, std::string* error) {
  if (!(o.max_curvature >= 0.0) || o.levels < 3 || o.levels % 2 == 0 || o.levels > 9 ||
      !(o.prior_sigmas >= 0.0) || o.refine_passes < 0 || o.refine_passes > 10) {
    *error =
        "curvature >= 0, an odd number of levels in 3..9, prior_sigmas >= 0 and refine_passes "
        "in 0..10 expected";
    return false;
  }
  for (int i : o.care) {
    if (i < 0 || i >= sys.num_params()) {
      *error = "care: a parameter index of the system expected";
      return false;
    }
  }
  if (o.targets.size() != 0 && o.targets.size() != sys.num_params()) {
    *error = "targets: one sigma per parameter (0: none) expected";
    return false;
  }
  if (o.start && !o.start->allFinite()) {
    *error = "start: a finite pose expected";
    return false;
  }
  return true;
}

}  // namespace

bool PlanOptions::IsValid(const System& sys, std::string* error) const {
  return ValidTiming(*this, error) && ValidLimits(*this, sys, error) &&
         ValidDesign(*this, sys, error) && info.IsValid(error);
}

Eigen::Vector3d StartPose(const Workspace& ws, const PlanOptions& o) {
  if (o.start) return *o.start;
  const Eigen::Vector2d c = ws.Centre();
  return {c.x(), c.y(), 0.0};
}

std::vector<Values> CandidateControls(const System& sys, const Eigen::VectorXd& params,
                                      const PlanOptions& o) {
  const int nc = sys.num_controls();
  std::vector<Values> out(1, Values{});
  for (int c = 0; c < nc; ++c) {
    std::vector<Values> next;
    for (const Values& base : out) {
      for (int l = 0; l < o.levels; ++l) {
        Values v = base;
        v[static_cast<size_t>(c)] =
            o.max_abs[static_cast<size_t>(c)] * (-1.0 + 2.0 * l / (o.levels - 1));
        next.push_back(v);
      }
    }
    out = std::move(next);
  }
  if (o.max_curvature > 0.0) {
    std::erase_if(out, [&](const Values& v) {
      const Eigen::Vector2d tw = plan_internal::TwistOf(sys, params, v);
      return std::abs(tw.y()) > o.max_curvature * std::abs(tw.x()) + 1e-12;
    });
  }
  return out;
}

Status SetPriorSigma(const System& sys, const std::map<std::string, double>& sigma,
                     Eigen::MatrixXd* prior_cov) {
  // Every entry checked before any is set: an error leaves the prior as it was.
  for (const auto& [name, s] : sigma) {
    if (sys.ParamIndex(name) < 0 || !std::isfinite(s) || s <= 0.0) {
      return Status::Error(
          "prior: '" + name + "' is not a parameter of this " + std::string(sys.model().name()) +
          " system with a finite, positive sigma (its parameters: " + ParamNames(sys.params()) +
          ")");
    }
  }
  for (const auto& [name, s] : sigma) SetSigmaAlone(sys.ParamIndex(name), s, prior_cov);
  return {};
}

Status HoldParameters(const System& sys, const std::map<std::string, double>& fixed,
                      Eigen::VectorXd* params, Eigen::MatrixXd* prior_cov, PlanOptions* o) {
  if (fixed.empty()) return {};
  const KinematicModel& model = sys.model();
  const std::string known = ParamNames(model.params());
  std::vector<bool> held(static_cast<size_t>(sys.num_params()), false);
  for (const auto& [name, v] : fixed) {
    const int i = model.ParamIndex(name);
    if (i < 0) {
      return Status::Error("fix: '" + name + "' is not a parameter of " +
                           std::string(model.name()) + " (its parameters: " + known + ")");
    }
    const std::string problem = ParamValueProblem(model.params()[static_cast<size_t>(i)], v);
    if (!problem.empty()) return Status::Error("fix: " + problem);
    (*params)[i] = v;
    SetSigmaAlone(i, kHeldSigmaFraction * sys.params()[static_cast<size_t>(i)].default_sigma,
                  prior_cov);
    held[static_cast<size_t>(i)] = true;
  }
  if (static_cast<int>(fixed.size()) >= model.num_params()) {
    return Status::Error("fix: every parameter of " + std::string(model.name()) + " is held (" +
                         known + "): nothing is left to plan for");
  }
  std::vector<int> care = o->care;
  if (care.empty()) {
    for (int i = 0; i < sys.num_params(); ++i) care.push_back(i);
  }
  std::erase_if(care, [&](int i) { return held[static_cast<size_t>(i)]; });
  o->care = care;
  return {};
}

Status PlanLimitsFrom(const System& sys, const std::map<std::string, double>& limits,
                      const std::map<std::string, double>& targets, PlanOptions* o) {
  const KinematicModel& model = sys.model();
  const size_t nc = static_cast<size_t>(sys.num_controls());
  o->max_abs.assign(nc, 0.0);
  o->max_accel.assign(nc, 0.0);
  for (const auto& [k, v] : limits) {
    const int c = model.ControlIndex(k);
    if (c >= 0) {
      o->max_abs[static_cast<size_t>(c)] = v;
    } else if (k == "accel") {
      for (double& x : o->max_accel) x = v;
    } else if (k.starts_with("accel_") && model.ControlIndex(k.substr(6)) >= 0) {
      o->max_accel[static_cast<size_t>(model.ControlIndex(k.substr(6)))] = v;
    } else if (k == "curvature") {
      o->max_curvature = v;
    } else {
      return Status::Error("limits: '" + k + "' is not a control of " + std::string(model.name()) +
                           ", accel, accel_<control> or curvature");
    }
  }
  std::string all;
  for (const auto& ci : model.controls()) all += (all.empty() ? "" : ", ") + ci.name;
  for (size_t c = 0; c < nc; ++c) {
    if (o->max_abs[c] == 0.0) {
      return Status::Error("limits: " + model.controls()[c].name +
                           "=.. missing (a limit for every control of " +
                           std::string(model.name()) + ": " + all + ")");
    }
  }
  o->targets = Eigen::VectorXd();
  o->care.clear();
  if (!targets.empty()) o->targets = Eigen::VectorXd::Zero(sys.num_params());
  for (const auto& [k, v] : targets) {
    const int i = sys.ParamIndex(k);
    if (i < 0 || !(v > 0.0)) {
      return Status::Error("targets: '" + k +
                           "' is not a parameter of this system, or its sigma is not > 0");
    }
    o->targets[i] = v;
    o->care.push_back(i);
  }
  return Status{};
}

std::vector<int> ScoredParams(const PlanOptions& o, int num_params) {
  if (!o.care.empty()) return o.care;
  std::vector<int> all(static_cast<size_t>(num_params));
  std::iota(all.begin(), all.end(), 0);
  return all;
}

double DesignScore(const Eigen::MatrixXd& cov, const Eigen::VectorXd& prior_sigma,
                   const PlanOptions& o) {
  const std::vector<int> idx = ScoredParams(o, static_cast<int>(cov.rows()));
  const int n = static_cast<int>(idx.size());
  Eigen::MatrixXd c(n, n);
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const int i = idx[static_cast<size_t>(a)], j = idx[static_cast<size_t>(b)];
      const double si = o.targets.size() > 0 && o.targets[i] > 0.0 ? o.targets[i] : prior_sigma[i];
      const double sj = o.targets.size() > 0 && o.targets[j] > 0.0 ? o.targets[j] : prior_sigma[j];
      c(a, b) = cov(i, j) / (si * sj);
    }
  }
  if (o.criterion == DesignCriterion::kA) return c.trace();
  if (o.criterion == DesignCriterion::kTargets) return c.diagonal().array().square().sum();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(c);
  return ldlt.vectorD().array().log().sum();
}

Status PlanMotion(const System& sys, const Eigen::VectorXd& params,
                  const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                  Motion* plan, std::vector<Motion>* usual) {
  std::string error;
  if (!o.IsValid(sys, &error)) return Status::Error("plan: " + error);
  plan_internal::Design d = plan_internal::DesignAtStart(sys, params, prior_cov, ws, o);
  if (!ws.Contains(d.info.MeasuredPose())) {
    return Status::Error("plan: the target at the start pose is outside the " + ws.Describe());
  }
  const std::vector<Values> grid = CandidateControls(sys, params, o);
  const Eigen::VectorXd prior_sigma = PriorSigma(prior_cov);
  // Whole segments, then the stop: at rest by duration_s whatever the last segment drove.
  const double stop_s = plan_internal::LongestStopSeconds(o, sys.num_controls());
  const int segments = static_cast<int>(std::floor((o.duration_s - stop_s) / o.segment_s + 1e-9));
  if (segments < 1) {
    return Status::Error("plan: a duration of " + std::to_string(o.duration_s) +
                         " s leaves no segment of " + std::to_string(o.segment_s) +
                         " s before the stop (" + std::to_string(stop_s) +
                         " s from the speed limits at the acceleration limits)");
  }
  // The robots within the prior: designed for once the design point's targets are reached
  // (DesignForJudges), and the plan is judged at them.
  const std::vector<plan_internal::Judge> robots =
      o.seed_with_usual ? plan_internal::RobotsToJudge(sys, params, prior_cov, o)
                        : std::vector<plan_internal::Judge>{};
  // The usual motions are searched on a second core while the plan is designed (they are
  // independent until the seeds; the inputs are only read), and timed at those robots.
  std::future<std::pair<std::vector<Motion>, std::vector<plan_internal::Judge>>> searched;
  if (o.seed_with_usual) {
    searched = std::async(std::launch::async, [&] {
      std::vector<Motion> found = UsualMotions(sys, params, prior_cov, ws, o);
      std::vector<plan_internal::Judge> judges =
          plan_internal::JudgesWithinPrior(sys, robots, prior_cov, ws, o, found);
      return std::make_pair(std::move(found), std::move(judges));
    });
  }
  // With targets, designed up to them first (and sooner, DesignSoonest), then on.
  const bool targets = o.targets.size() > 0;
  bool ok = plan_internal::DesignSegments(sys, ws, o, grid, prior_sigma, segments, targets, &d);
  if (ok && targets && o.refine_passes > 0 &&
      plan_internal::WorstTargetRatio(d.info.Covariance(), o) <= 1.0) {
    plan_internal::DesignSoonest(sys, params, prior_cov, ws, o, grid, &d);
  }
  // Once the design point's targets are reached, designed on for the robots within the
  // prior that have not reached theirs (DesignForJudges), then greedily to the duration.
  if (ok && targets) {
    int left = segments - static_cast<int>(d.chosen.size());
    left -= plan_internal::DesignForJudges(sys, prior_cov, ws, o, grid, robots, left, &d);
    ok = plan_internal::DesignSegments(sys, ws, o, grid, prior_sigma, left, false, &d);
  }
  if (!ok) {
    const std::string when =
        d.t_s > 0.0 ? " after " + ShortNumber(d.t_s) + " s" : " from the start";
    return Status::Error("plan: no control keeps every robot within the prior inside the " +
                         ws.Describe() + when + "; widen the workspace or lower the speed limits");
  }
  plan->name = "plan";
  plan->controls = std::move(d.u);
  plan->segment_starts_s = {0.0};
  plan_internal::AppendStopAndRest(&plan->controls, d.t_s, o.duration_s, o, &d.now);
  EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, plan);
  if (o.seed_with_usual) {
    std::vector<Motion> compared;
    std::vector<Motion>& motions = usual != nullptr ? *usual : compared;
    auto [found, judges] = searched.get();
    motions = std::move(found);
    plan_internal::SeedWithUsual(sys, params, prior_cov, ws, o, grid, motions, robots, plan);
    KeepTheBetter(o, prior_sigma, motions, plan);
    plan_internal::JudgePlan(sys, prior_cov, ws, o, judges, plan);
  }
  return Status{};
}

}  // namespace kincal
