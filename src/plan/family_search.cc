#include "plan/family_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include "plan/shaping.h"

namespace kincal::plan_internal {
namespace {

constexpr std::array<double, 4> kSpeeds = {0.4, 0.6, 0.8, 1.0};  // of the fastest
constexpr double kFinerSpeed = 0.1;                     // the finer search's speeds, each way
constexpr double kFinerSize = 0.5;                      // and sizes, in steps of the grid
constexpr double kRaceFactor = 2.0, kRaceSlackS = 1.0;  // how far candidates are followed

struct Candidate {
  Motion m;
  double size, speed;
};

// Every candidate's rank, those that stay in at the design point first, best first.
std::vector<std::pair<double, size_t>> Ranked(const std::vector<Candidate>& all,
                                              const PlanOptions& o,
                                              const Eigen::VectorXd& prior_sigma) {
  std::vector<std::pair<double, size_t>> order;
  for (size_t k = 0; k < all.size(); ++k) {
    const double penalty = all[k].m.stays_in ? 0.0 : std::numeric_limits<double>::max();
    order.emplace_back(std::max(MotionRank(all[k].m, o, prior_sigma), penalty), k);
  }
  std::stable_sort(order.begin(), order.end());
  return order;
}

// The best that keeps every robot within the prior inside, whole or stopped, and before it
// when better the best at the design point only (BestOfFamily).
std::vector<Motion> BestOf(std::vector<Candidate> all, const System& sys,
                           const Eigen::VectorXd& params, const Eigen::MatrixXd& prior_cov,
                           const Workspace& ws, const PlanOptions& o) {
  const auto order = Ranked(all, o, prior_cov.diagonal().cwiseSqrt());
  std::vector<Motion> out;
  for (const auto& [rank, k] : order) {
    Motion& m = all[k].m;
    if (!m.stays_in) break;
    if (EveryRobotStaysIn(sys, params, prior_cov, ws, o, m.controls)) {
      out.push_back(std::move(m));
      return out;
    }
    std::optional<Motion> stopped = StoppedAtTargets(sys, params, prior_cov, ws, o, m);
    if (stopped && stopped->stays_in &&
        EveryRobotStaysIn(sys, params, prior_cov, ws, o, stopped->controls)) {
      out.push_back(std::move(*stopped));
      return out;
    }
    m.every_robot_stays_in = false;
    if (out.empty()) out.push_back(m);
  }
  if (out.empty()) {
    out.push_back(std::move(all[order.front().second].m));
    out.back().every_robot_stays_in = false;
  }
  return out;
}

}  // namespace

std::vector<double> SizesBetween(double lo, double hi, int n) {
  if (!(lo > 0.0) || !(lo < hi) || n < 2) return {hi};
  std::vector<double> out;
  for (int k = 0; k < n; ++k) out.push_back(lo * std::pow(hi / lo, k / (n - 1.0)));
  return out;
}

std::vector<Motion> BestOfFamily(const FamilyMember& member, const FamilySizes& sizes,
                                 const System& sys, const Eigen::VectorXd& params,
                                 const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                 const PlanOptions& o) {
  std::vector<Candidate> all;
  // With targets, each candidate is followed only to twice the soonest time any has
  // reached them (a second more): one that needs longer is not the family's best. Those
  // returned are evaluated whole.
  double soonest = std::numeric_limits<double>::infinity();
  const auto add = [&](double size, double speed) {
    std::optional<Motion> m = member(size, speed);
    if (!m) return;
    PlanOptions race = o;
    race.duration_s = std::min(o.duration_s, kRaceFactor * soonest + kRaceSlackS);
    EvaluateMotion(sys, params, prior_cov, ws, race, kCurveStepS, &*m);
    if (!m->curve.extrapolated) soonest = std::min(soonest, m->curve.time_to_target_s);
    all.push_back({std::move(*m), size, speed});
  };
  const std::vector<double> grid = SizesBetween(sizes.smallest, sizes.largest, sizes.count);
  for (double size : grid) {
    for (double k : kSpeeds) add(size, k);
  }
  if (all.empty()) return {};
  // Finer about the best at the design point: a family's time to the targets jumps with
  // where its turns fall, and the coarse grid alone misses the best by a second or more.
  const auto order = Ranked(all, o, prior_cov.diagonal().cwiseSqrt());
  if (all[order.front().second].m.stays_in) {
    const double size = all[order.front().second].size, k = all[order.front().second].speed;
    const double step = grid.size() > 1 ? std::pow(grid[1] / grid[0], kFinerSize) : 1.0;
    const std::vector<double> scales =
        step > 1.0 ? std::vector<double>{1.0 / step, 1.0, step} : std::vector<double>{1.0};
    for (double q : scales) {
      for (double dk : {-kFinerSpeed, 0.0, kFinerSpeed}) {
        if ((q == 1.0 && dk == 0.0) || k + dk <= 0.0 || k + dk > 1.0 + 1e-9) continue;
        add(size * q, k + dk);
      }
    }
  }
  std::vector<Motion> best = BestOf(std::move(all), sys, params, prior_cov, ws, o);
  for (Motion& m : best) {
    if (m.unstopped.empty()) EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, &m);
  }
  return best;
}

std::optional<Motion> StoppedAtTargets(const System& sys, const Eigen::VectorXd& params,
                                       const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                       const PlanOptions& o, const Motion& m) {
  const double t = ReachedAt(m);
  const int nc = sys.num_controls();
  if (!std::isfinite(t) || t > o.duration_s - LongestStopSeconds(o, nc) + 1e-9) {
    return std::nullopt;
  }
  Motion out;
  char name[48];
  std::snprintf(name, sizeof(name), ", stopped at %g s", t);
  out.name = m.name + name;
  out.segment_starts_s = m.segment_starts_s;
  out.unstopped = m.controls;
  out.controls = ControlSignal(nc, 0);
  AppendSamplesBefore(&out.controls, m.controls, t);
  Values now = m.controls.At(t);
  AppendStopAndRest(&out.controls, t, o.duration_s, o, &now);
  EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, &out);
  return out;
}

}  // namespace kincal::plan_internal
