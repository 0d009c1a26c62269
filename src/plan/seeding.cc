#include "plan/seeding.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

#include "plan/greedy.h"
#include "plan/judged_design.h"

namespace kincal::plan_internal {
namespace {

// How much of a usual motion's time to the targets seeds a design.
constexpr std::array<double, 3> kSeedShares = {0.5, 0.75, 1.0};

struct Seeded {
  Design design;
  const Motion* seed;
  double seed_s;
};

}  // namespace

bool SeedWithUsual(const System& sys, const Eigen::VectorXd& params,
                   const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                   const std::vector<Values>& grid, const std::vector<Motion>& usual,
                   const std::vector<Judge>& judges, Motion* plan) {
  if (o.targets.size() == 0) return false;
  const Eigen::VectorXd prior_sigma = prior_cov.diagonal().cwiseSqrt();
  const double drive_end_s = o.duration_s - LongestStopSeconds(o, sys.num_controls());
  double best_s = ReachedAt(*plan);
  std::optional<Seeded> best;
  for (const Motion& m : usual) {
    const double reach = ReachedAt(m);
    if (m.segment_starts_s.size() != 1 || !m.stays_in || !std::isfinite(reach)) continue;
    for (double share : kSeedShares) {
      // On the control samples' grid, and early enough to be worth designing on from.
      const double seed_s = std::round(share * reach * o.control_rate_hz) / o.control_rate_hz;
      if (!(seed_s > 0.0) || seed_s >= best_s || seed_s >= drive_end_s) continue;
      Design d = DesignAtStart(sys, params, prior_cov, ws, o);
      if (!DesignFromSeed(sys, ws, o, m.controls, seed_s, &d)) continue;
      // Only as many segments as could still beat the best so far.
      const int count = static_cast<int>(
          std::ceil((std::min(best_s, drive_end_s) - seed_s) / o.segment_s - 1e-9));
      if (!DesignSegments(sys, ws, o, grid, prior_sigma, count, true, &d) ||
          WorstTargetRatio(d.info.Covariance(), o) > 1.0 || d.t_s >= best_s) {
        continue;
      }
      best_s = d.t_s;
      best = Seeded{std::move(d), &m, seed_s};
    }
  }
  if (!best) return false;
  Design& d = best->design;
  // On to the duration; a design that finds no safe control stops where it is (each
  // segment's stop was checked).
  int left = static_cast<int>(std::floor((drive_end_s - d.t_s) / o.segment_s + 1e-9));
  left -= DesignForJudges(sys, prior_cov, ws, o, grid, judges, left, &d);
  DesignSegments(sys, ws, o, grid, prior_sigma, left, false, &d);
  Motion seeded;
  // Named after the seed's motion (a stopped one's name says where it stopped).
  const std::string& seed = best->seed->name;
  char name[200];
  std::snprintf(name, sizeof(name), "plan (%s for %g s, then designed)",
                seed.substr(0, seed.rfind(", stopped at")).c_str(), best->seed_s);
  seeded.name = name;
  seeded.controls = std::move(d.u);
  seeded.segment_starts_s = {0.0};
  AppendStopAndRest(&seeded.controls, d.t_s, o.duration_s, o, &d.now);
  EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, &seeded);
  if (!(MotionRank(seeded, o, prior_sigma) < MotionRank(*plan, o, prior_sigma))) return false;
  *plan = std::move(seeded);
  return true;
}

}  // namespace kincal::plan_internal
