#include "plan/within_prior.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "plan/fleet.h"

namespace kincal::plan_internal {
namespace {

bool Physical(const System& sys, const Eigen::VectorXd& p) {
  for (int i = 0; i < p.size(); ++i) {
    if (p[i] < sys.params()[static_cast<size_t>(i)].min_value) return false;
  }
  return true;
}

// Whether a displacement moves only parameters held (HoldParameters: a sigma of
// kHeldSigmaFraction of the generic one; ten times that is still held).
bool HeldAxis(const System& sys, const Eigen::VectorXd& d, double k) {
  for (int i = 0; i < d.size(); ++i) {
    const double held =
        10.0 * k * kHeldSigmaFraction * sys.params()[static_cast<size_t>(i)].default_sigma;
    if (std::abs(d[i]) > held) return false;
  }
  return true;
}

// "r_l -3 sigma" for a robot along one parameter (a diagonal prior); else "prior axis
// a +3 sigma", the sign that of the pair (RobotsWithinPrior: + then -); "the design point"
// for none. `k` is the robot's index in RobotsWithinPrior.
std::string JudgeName(const System& sys, const Eigen::VectorXd& scaled, double sigmas, size_t k) {
  if (k == 0) return "the design point";
  Eigen::Index i = 0;
  scaled.cwiseAbs().maxCoeff(&i);
  const bool along = std::abs(scaled[i]) >= 0.99 * scaled.norm();
  const bool plus = along ? scaled[i] > 0.0 : k % 2 == 1;
  char tail[48];
  std::snprintf(tail, sizeof(tail), " %s%g sigma", plus ? "+" : "-", sigmas);
  if (along) return sys.params()[static_cast<size_t>(i)].name + tail;
  return "prior axis " + std::to_string((k + 1) / 2) + tail;
}

// When `u` brings robot p to the targets, or infinity when not within o.duration_s.
double TimeAt(const System& sys, const Eigen::VectorXd& p, const Eigen::MatrixXd& prior_cov,
              const Workspace& ws, const PlanOptions& o, const ControlSignal& u) {
  Motion m;
  m.controls = u;
  m.segment_starts_s = {0.0};
  EvaluateMotion(sys, p, prior_cov, ws, o, kCurveStepS, &m);
  return ReachedAt(m);
}

double QuickestUsual(const System& sys, const Eigen::VectorXd& p, const Eigen::MatrixXd& prior_cov,
                     const Workspace& ws, const PlanOptions& o, const std::vector<Motion>& usual) {
  double best = std::numeric_limits<double>::infinity();
  for (const Motion& m : usual) {
    if (m.segment_starts_s.size() != 1 || !m.stays_in || !m.every_robot_stays_in ||
        !std::isfinite(ReachedAt(m))) {
      continue;
    }
    // A motion stopped at the design point's targets is driven on by a robot that needs longer.
    best = std::min(
        best, TimeAt(sys, p, prior_cov, ws, o, m.unstopped.empty() ? m.controls : m.unstopped));
  }
  return best;
}

}  // namespace

std::vector<Judge> RobotsToJudge(const System& sys, const Eigen::VectorXd& params,
                                 const Eigen::MatrixXd& prior_cov, const PlanOptions& o) {
  std::vector<Judge> judges;
  if (o.targets.size() == 0) return judges;
  const Eigen::VectorXd sigma = prior_cov.diagonal().cwiseSqrt();
  const std::vector<Eigen::VectorXd> robots = RobotsWithinPrior(params, prior_cov, o.prior_sigmas);
  for (size_t k = 0; k < robots.size(); ++k) {
    const Eigen::VectorXd scaled = (robots[k] - params).cwiseQuotient(sigma);
    if (k > 0 && HeldAxis(sys, robots[k] - params, o.prior_sigmas)) continue;
    if (!Physical(sys, robots[k])) continue;
    judges.push_back({JudgeName(sys, scaled, o.prior_sigmas, k), robots[k], 0.0});
  }
  return judges;
}

std::vector<Judge> JudgesWithinPrior(const System& sys, const std::vector<Judge>& robots,
                                     const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                     const PlanOptions& o, const std::vector<Motion>& usual) {
  std::vector<Judge> judges;
  for (const Judge& robot : robots) {
    const double t = QuickestUsual(sys, robot.params, prior_cov, ws, o, usual);
    if (std::isfinite(t)) judges.push_back({robot.name, robot.params, t});
  }
  return judges;
}

void JudgePlan(const System& sys, const Eigen::MatrixXd& prior_cov, const Workspace& ws,
               const PlanOptions& o, const std::vector<Judge>& judges, Motion* plan) {
  plan->within_prior.clear();
  for (const Judge& j : judges) {
    plan->within_prior.push_back(
        {j.name, j.usual_s, TimeAt(sys, j.params, prior_cov, ws, o, plan->controls)});
  }
}

}  // namespace kincal::plan_internal

namespace kincal {

double SpeedUp(const PriorRobotTimes& t) {
  return std::isfinite(t.plan_s) && t.plan_s > 0.0 ? t.usual_s / t.plan_s : 0.0;
}

std::pair<double, std::string> LeastSpeedUp(const Motion& plan) {
  std::pair<double, std::string> least{0.0, ""};
  for (const PriorRobotTimes& t : plan.within_prior) {
    const double s = SpeedUp(t);
    if (least.second.empty() || s < least.first) least = {s, t.robot};
  }
  return least;
}

}  // namespace kincal
