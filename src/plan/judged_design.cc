#include "plan/judged_design.h"

#include <future>
#include <optional>
#include <utility>

namespace kincal::plan_internal {
namespace {

// Each candidate is judged held this many segments beyond its own: one segment of a
// straight run or a turn tells little, and the greedy choice on one segment alone spins in
// place (on issue 34's command, the robot with the right wheel 45 % larger reaches the
// targets at 12.5 s so, at 7.75 s with two segments more).
constexpr int kHorizonSegments = 2;

// The judges not yet at the targets along d's controls, each with what it then knows.
std::vector<DesignInformation> JudgesShort(const System& sys, const Eigen::MatrixXd& prior_cov,
                                           const Workspace& ws, const PlanOptions& o,
                                           const std::vector<Judge>& judges, const Design& d) {
  std::vector<DesignInformation> short_of;
  const Eigen::Vector3d start = StartPose(ws, o);
  for (const Judge& j : judges) {
    DesignInformation info(sys, j.params, prior_cov, o.info);
    info.StartSegment(start, 0.0, d.u);
    info.Advance(d.t_s, d.u);
    if (WorstTargetRatio(info.Covariance(), o) > 1.0) short_of.push_back(std::move(info));
  }
  return short_of;
}

// Drives each judge's information through trial t's segment (to t1_s) and returns the sum
// of their DesignScores with t's control held kHorizonSegments more.
double ScoreForJudges(const PlanOptions& o, const Eigen::VectorXd& prior_sigma, double t1_s,
                      const Trial& t, std::vector<DesignInformation>* judges) {
  const double ahead_s = t1_s + kHorizonSegments * o.segment_s;
  ControlSignal held = t.u;
  Values at = t.end;
  AppendSlewed(&held, t1_s, ahead_s, t.value, o, &at);
  double score = 0.0;
  for (DesignInformation& info : *judges) {
    info.Advance(t1_s, t.u);
    DesignInformation ahead = info;
    ahead.Advance(ahead_s, held);
    score += DesignScore(ahead.Covariance(), prior_sigma, o);
  }
  return score;
}

}  // namespace

int DesignForJudges(const System& sys, const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                    const PlanOptions& o, const std::vector<Values>& grid,
                    const std::vector<Judge>& judges, int count, Design* d) {
  if (o.targets.size() == 0 || WorstTargetRatio(d->info.Covariance(), o) > 1.0) return 0;
  const Eigen::VectorXd prior_sigma = prior_cov.diagonal().cwiseSqrt();
  std::vector<DesignInformation> open = JudgesShort(sys, prior_cov, ws, o, judges, *d);
  std::vector<std::optional<Trial>> trials(grid.size());
  std::vector<std::vector<DesignInformation>> advanced(grid.size());
  // Candidates [begin, end) tried, each judged (the inputs are only read).
  auto try_range = [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      trials[c] = TryCandidate(sys, ws, o, prior_sigma, grid[c], *d);
      if (!trials[c]) continue;
      advanced[c] = open;
      trials[c]->score =
          ScoreForJudges(o, prior_sigma, d->t_s + o.segment_s, *trials[c], &advanced[c]);
    }
  };
  int designed = 0;
  for (; designed < count && !open.empty(); ++designed) {
    // Half the grid on a second thread (it shares the second core with the usual motions'
    // search while that runs).
    std::future<void> half = std::async(std::launch::async, try_range, 0, grid.size() / 2);
    try_range(grid.size() / 2, grid.size());
    half.get();
    size_t best = grid.size();
    for (size_t c = 0; c < grid.size(); ++c) {
      if (trials[c] && (best == grid.size() || trials[c]->score < trials[best]->score)) best = c;
    }
    if (best == grid.size()) break;
    KeepTrial(sys, ws, o, &*trials[best], d);
    open.clear();
    for (DesignInformation& info : advanced[best]) {
      if (WorstTargetRatio(info.Covariance(), o) > 1.0) open.push_back(std::move(info));
    }
  }
  return designed;
}

}  // namespace kincal::plan_internal
