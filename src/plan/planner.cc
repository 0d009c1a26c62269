#include "kincal/plan/planner.h"

#include <Eigen/Dense>
#include <cmath>
#include <numeric>
#include <optional>

#include "kincal/angles.h"
#include "plan/fleet.h"
#include "plan/refine.h"
#include "plan/shaping.h"

namespace kincal {
namespace {

using plan_internal::Values;

using plan_internal::DriveFleet;
using plan_internal::Fleet;
using plan_internal::FleetAtStart;
using plan_internal::kFleetCheckS;

constexpr double kSettleS = 3.0;      // a stop is followed this long beyond its slewing (s)
constexpr double kAnticipateS = 1.0;  // the most negative delay driven exactly (s)

Eigen::VectorXd PriorSigma(const Eigen::MatrixXd& prior_cov) {
  return prior_cov.diagonal().cwiseSqrt();
}

// One candidate driven for a segment: its controls, where they end, what is then known.
struct Trial {
  double score;
  ControlSignal u;
  Values end;
  DesignInformation info;
  Values value;  // the segment's control
};

// Tries one candidate: drives it for a segment and a stop after it. Nothing when a robot
// within the prior would leave the workspace.
std::optional<Trial> TryCandidate(const System& sys, const Workspace& ws, const PlanOptions& o,
                                  const Eigen::VectorXd& prior_sigma, const Values& cand, double t0,
                                  const ControlSignal& u0, const Values& now,
                                  const DesignInformation& info0, const Fleet& fleet0) {
  ControlSignal u = u0;
  Values at = now;
  const double t1 = t0 + o.segment_s;
  plan_internal::AppendSlewed(&u, t0, t1, cand, o, &at);
  // The stop after it: until every robot within the prior has come to rest (a lag or a
  // delay at the prior's 3 sigma keeps one moving for a while).
  ControlSignal braked = u;
  Values b = at;
  const double settle = t1 + o.segment_s + kSettleS;
  plan_internal::AppendSlewed(&braked, t1, settle, Values{}, o, &b);
  Fleet fleet = fleet0;
  if (!DriveFleet(sys, braked, ws, settle, kFleetCheckS, true, &fleet)) return std::nullopt;
  DesignInformation info = info0;
  info.Advance(t1, u);
  const double score = DesignScore(info.Covariance(), prior_sigma, o);
  return Trial{score, std::move(u), at, std::move(info), cand};
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
// (UsualMotions checked it), whichever ranks better. `usual` receives the usual motions.
void KeepTheBetter(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   Motion* plan, std::vector<Motion>* usual) {
  *usual = UsualMotions(sys, params, prior_cov, ws, o);
  const Eigen::VectorXd prior_sigma = PriorSigma(prior_cov);
  double best = MotionRank(*plan, o, prior_sigma);
  const Motion* better = nullptr;
  for (const Motion& m : *usual) {
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
  if (!(o.duration_s > 0.0 && o.duration_s <= 3600.0) ||
      !(o.control_rate_hz >= 1.0 && o.control_rate_hz <= 1000.0) ||
      !(o.segment_s >= 1.0 / o.control_rate_hz && o.segment_s <= o.duration_s)) {
    *error =
        "duration in (0, 3600] s, rate in [1, 1000] Hz and a segment between one control "
        "period and the duration expected";
    return false;
  }
  return true;
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

Status HoldParameters(const System& sys, const std::map<std::string, double>& fixed,
                      Eigen::VectorXd* params, Eigen::MatrixXd* prior_cov, PlanOptions* o) {
  if (fixed.empty()) return {};
  const KinematicModel& model = sys.model();
  const std::string known = ParamNames(model.params());
  std::vector<bool> held(static_cast<size_t>(sys.num_params()), false);
  for (const auto& [name, v] : fixed) {
    const int i = model.ParamIndex(name);
    if (i < 0 || !std::isfinite(v)) {
      return Status::Error("fix: '" + name + "' is not a parameter of " +
                           std::string(model.name()) +
                           " with a finite value (its parameters: " + known + ")");
    }
    (*params)[i] = v;
    const double s = kHeldSigmaFraction * sys.params()[static_cast<size_t>(i)].default_sigma;
    prior_cov->row(i).setZero();
    prior_cov->col(i).setZero();
    (*prior_cov)(i, i) = s * s;
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
  const Eigen::Vector3d start = StartPose(ws, o);
  plan->name = "plan";
  plan->controls = ControlSignal(sys.num_controls(), 0);
  plan->segment_starts_s = {0.0};
  DesignInformation info(sys, params, prior_cov, o.info);
  info.StartSegment(start, 0.0, plan->controls);
  Fleet fleet = FleetAtStart(sys, params, prior_cov, start, o, plan->controls);
  if (!ws.Contains(info.MeasuredPose())) {
    return Status::Error("plan: the target at the start pose is outside the " + ws.Describe());
  }
  const std::vector<Values> grid = CandidateControls(sys, params, o);
  const Eigen::VectorXd prior_sigma = PriorSigma(prior_cov);
  Values now{};
  // Whole segments, then the stop: at rest by duration_s whatever the last segment drove.
  const double stop_s = plan_internal::LongestStopSeconds(o, sys.num_controls());
  const int segments = static_cast<int>(std::floor((o.duration_s - stop_s) / o.segment_s + 1e-9));
  if (segments < 1) {
    return Status::Error("plan: a duration of " + std::to_string(o.duration_s) +
                         " s leaves no segment of " + std::to_string(o.segment_s) +
                         " s before the stop (" + std::to_string(stop_s) +
                         " s from the speed limits at the acceleration limits)");
  }
  std::vector<Values> chosen;
  for (int s = 0; s < segments; ++s) {
    const double t0 = s * o.segment_s;
    std::optional<Trial> best;
    for (const Values& cand : grid) {
      std::optional<Trial> t =
          TryCandidate(sys, ws, o, prior_sigma, cand, t0, plan->controls, now, info, fleet);
      if (t && (!best || t->score < best->score)) best = std::move(t);
    }
    if (!best) {
      return Status::Error("plan: no control keeps every robot within the prior inside the " +
                           ws.Describe() + " after " + std::to_string(t0) +
                           " s; widen the workspace or lower the speed limits");
    }
    plan->controls = std::move(best->u);
    chosen.push_back(best->value);
    now = best->end;
    info = std::move(best->info);
    // The fleet stays kAnticipateS behind the plan: a robot with a negative delay (a
    // camera clock behind the robot's) moves by commands not yet chosen, and is driven
    // through them only when they are.
    DriveFleet(sys, plan->controls, ws, std::max(0.0, t0 + o.segment_s - kAnticipateS),
               kFleetCheckS, false, &fleet);
  }
  plan_internal::AppendStopAndRest(&plan->controls, segments * o.segment_s, o.duration_s, o, &now);
  if (o.refine_passes > 0 && plan_internal::RefineSegments(sys, params, prior_cov, ws, o, grid,
                                                           o.refine_passes, &chosen) > 0) {
    plan->controls = plan_internal::ControlsOfSegments(chosen, o, sys.num_controls());
  }
  EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, plan);
  if (o.seed_with_usual) {
    std::vector<Motion> compared;
    KeepTheBetter(sys, params, prior_cov, ws, o, plan, usual != nullptr ? usual : &compared);
  }
  return Status{};
}

}  // namespace kincal
