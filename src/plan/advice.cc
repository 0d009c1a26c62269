#include "kincal/plan/advice.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "kincal/angles.h"
#include "plan/shaping.h"

namespace kincal {
namespace {

using plan_internal::Values;

// Below these a twist component counts as zero in words.
constexpr double kStillSpeed = 0.01;  // m/s
constexpr double kStillTurn = 0.02;   // rad/s
// The greedy plan that predicts the time to the targets: an open floor, at most this long.
constexpr double kMaxPredictS = 600.0;
constexpr double kPredictChunkS = 60.0;

Eigen::VectorXd Scales(const Eigen::MatrixXd& cov, const PlanOptions& o) {
  Eigen::VectorXd s = cov.diagonal().cwiseSqrt();
  for (int i = 0; i < o.targets.size(); ++i) {
    if (o.targets[i] > 0.0) s[i] = o.targets[i];
  }
  return s;
}

// The target's pose along `controls` held for horizon_s from rest, relative to its start.
std::vector<Eigen::Vector3d> PathOf(const System& sys, const Eigen::VectorXd& params,
                                    const Eigen::MatrixXd& cov, const PlanOptions& o,
                                    const Values& controls, double horizon_s) {
  ControlSignal u(sys.num_controls(), 0);
  Values now{};
  plan_internal::AppendSlewed(&u, 0.0, horizon_s, controls, o, &now);
  DesignInformation info(sys, params, cov, o.info);
  info.StartSegment(Eigen::Vector3d::Zero(), 0.0, u);
  const Eigen::Vector3d start = info.MeasuredPose();
  const double c = std::cos(start.z()), s = std::sin(start.z());
  std::vector<Eigen::Vector3d> path;
  const int steps = static_cast<int>(std::ceil(horizon_s / Advice::kPathStepS - 1e-9));
  for (int k = 0; k <= steps; ++k) {
    if (k > 0) info.Advance(std::min(horizon_s, k * Advice::kPathStepS), u);
    const Eigen::Vector3d q = info.MeasuredPose();
    const Eigen::Vector2d d = q.head<2>() - start.head<2>();
    path.emplace_back(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), WrapAngle(q.z() - start.z()));
  }
  return path;
}

// The worst scored parameter: largest sigma over its target.
void FindWorst(const Eigen::VectorXd& sigma, const Eigen::VectorXd& scale, const PlanOptions& o,
               Advice* a) {
  for (int i : ScoredParams(o, static_cast<int>(sigma.size()))) {
    const double r = sigma[i] / scale[i];
    if (r > a->worst_ratio) {
      a->worst_ratio = r;
      a->worst = i;
    }
  }
}

// Driving time to the targets along greedy plans from the estimate, a minute at a time
// (each minute's plan starts from the covariance the last one left).
double TimeToTargets(const System& sys, const Eigen::VectorXd& p, Eigen::MatrixXd cov,
                     PlanOptions o) {
  if (o.targets.size() == 0) return std::numeric_limits<double>::quiet_NaN();
  const auto floor = MakeArena(-1e4, -1e4, 1e4, 1e4);
  o.duration_s = kPredictChunkS;
  o.prior_sigmas = 0.0;       // nothing to keep in view on an open floor
  o.seed_with_usual = false;  // "greedy plans", as the advice says
  o.refine_passes = 0;
  for (double done = 0.0; done < kMaxPredictS; done += kPredictChunkS) {
    Motion m;
    if (!PlanMotion(sys, p, cov, *floor, o, &m).ok()) break;
    if (!m.curve.extrapolated && std::isfinite(m.curve.time_to_target_s)) {
      return done + m.curve.time_to_target_s;
    }
    cov = m.curve.sigma.back().cwiseAbs2().asDiagonal();  // what is known after this minute
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

std::string DescribeMotion(const Eigen::Vector2d& tw, double seconds) {
  char buf[160];
  const double v = tw.x(), w = tw.y();
  const char* side = w > 0.0 ? "left" : "right";
  if (std::abs(v) < kStillSpeed && std::abs(w) < kStillTurn) {
    std::snprintf(buf, sizeof buf, "stand still for %.3g s", seconds);
  } else if (std::abs(v) < kStillSpeed) {
    std::snprintf(buf, sizeof buf, "turn in place %s at %.2f rad/s for %.3g s", side, std::abs(w),
                  seconds);
  } else if (std::abs(w) < kStillTurn) {
    std::snprintf(buf, sizeof buf, "drive %s at %.2f m/s for %.3g s",
                  v > 0.0 ? "forward" : "backward", std::abs(v), seconds);
  } else {
    std::snprintf(
        buf, sizeof buf, "drive %s at %.2f m/s turning %s at %.2f rad/s (radius %.2f m) for %.3g s",
        v > 0.0 ? "forward" : "backward", std::abs(v), side, std::abs(w), std::abs(v / w), seconds);
  }
  return buf;
}

Status Advise(const System& sys, const Eigen::VectorXd& params, const Eigen::MatrixXd& cov,
              const PlanOptions& o, double horizon_s, Advice* out) {
  std::string error;
  if (!o.IsValid(sys, &error)) return Status::Error("advice: " + error);
  if (!(horizon_s > 0.0 && horizon_s <= 60.0)) {
    return Status::Error("advice: a horizon in (0, 60] s expected");
  }
  Advice a;
  a.sigma_now = cov.diagonal().cwiseSqrt();
  const Eigen::VectorXd scale = Scales(cov, o);
  FindWorst(a.sigma_now, scale, o, &a);
  double best = std::numeric_limits<double>::infinity();
  std::vector<Values> grid = CandidateControls(sys, params, o);
  std::reverse(grid.begin(), grid.end());  // of two equal motions, the forward one
  for (const Values& cand : grid) {
    ControlSignal u(sys.num_controls(), 0);
    Values now{};
    plan_internal::AppendSlewed(&u, 0.0, horizon_s, cand, o, &now);
    DesignInformation info(sys, params, cov, o.info);
    info.StartSegment(Eigen::Vector3d::Zero(), 0.0, u);
    info.Advance(horizon_s, u);
    const Eigen::MatrixXd after = info.Covariance();
    const double score = DesignScore(after, a.sigma_now, o);
    if (score < best) {
      best = score;
      a.controls = cand;
      a.sigma_after = after.diagonal().cwiseSqrt();
    }
  }
  a.duration_s = horizon_s;
  a.twist = plan_internal::TwistOf(sys, params, a.controls);
  a.motion = DescribeMotion(a.twist, horizon_s);
  a.path = PathOf(sys, params, cov, o, a.controls, horizon_s);
  a.time_to_target_s = TimeToTargets(sys, params, cov, o);
  *out = std::move(a);
  return Status{};
}

}  // namespace kincal
