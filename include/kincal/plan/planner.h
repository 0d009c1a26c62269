// kincal plan: an open-loop control sequence that calibrates a robot fastest, and the
// motions people use today evaluated on the same footing.
//
// The plan is built one segment at a time (greedy sequential design): from the motion so
// far, every candidate control (a grid over each channel's limits) is driven for one
// segment, with the channels slewing at their acceleration limits, and the candidate
// whose predicted posterior (DesignInformation) scores best is kept. A candidate is
// allowed only if the target stays in the workspace along it and along a stop after it,
// for every robot within the k-sigma ellipsoid of the prior: the robots at +-k sigma
// along each principal axis are driven as they are, and the ellipsoid between them is
// checked through the spread of poses they imply (to first order). With targets, the
// design is first made up to them under each criterion and looked ahead on (the soonest
// kept, src/plan/refine.h), and seeded with the usual motions (src/plan/seeding.h); the
// rest of the duration is then designed on, first for the robots at +-k sigma along the
// prior's axes still short of the targets (src/plan/judged_design.h), then greedily.
//
// Score (the parameters `care`, each scaled by its target sigma, or its prior sigma when
// it has none): A-optimal, the sum of the scaled variances; D-optimal, the log
// determinant of the scaled covariance; targets (the default), the sum of the scaled
// variances squared: the time to every target is the slowest parameter's, and squaring
// makes the parameter farthest from its target count most (on the reference case it
// reaches the targets a tenth sooner than A-optimal).
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/plan/design_information.h"
#include "kincal/plan/workspace.h"
#include "kincal/status.h"
#include "kincal/system.h"

namespace kincal {

enum class DesignCriterion { kA, kD, kTargets };

// The longest plan, and the fastest control rate, a plan is made for.
inline constexpr double kMaxPlanDurationS = 3600.0;
inline constexpr double kMaxPlanControlRateHz = 1000.0;

struct PlanOptions {
  double duration_s = 60.0;       // (0, kMaxPlanDurationS]
  double control_rate_hz = 20.0;  // samples of the output sequence per second, >= 1
  double segment_s = 0.5;         // one decision per segment: a control period to duration_s
  std::vector<double> max_abs;    // per control channel, > 0
  std::vector<double> max_accel;  // per channel, units per second; 0 or empty: none
  double max_curvature = 0.0;     // |omega / v| (1/m) at the design point; 0: none
  int levels = 5;                 // grid levels per channel (odd, >= 3)
  double prior_sigmas = 3.0;      // the robots that must stay in view
  DesignCriterion criterion = DesignCriterion::kTargets;
  std::vector<int> care;    // parameter indices scored; empty: all
  Eigen::VectorXd targets;  // target sigma per parameter; 0 or empty: none
  DesignInformationOptions info;
  // Robot pose (x, y, theta) where the motion starts, at rest; unset: the workspace's
  // centre, heading along +x.
  std::optional<Eigen::Vector3d> start;
  // Never worse than the usual motions: designs seeded with each of them
  // (src/plan/seeding.h), and the best of them (UsualMotions) that keeps every robot within
  // the prior inside, replace the plan when better (MotionRank). It costs the usual
  // motions' search (some 3 s of a second core for 60 s, run while the plan is designed).
  // With it too, once the design point has reached the targets, the next segments are
  // designed for the robots within the prior that have not (src/plan/judged_design.h).
  // kincald's guidance, which plans short legs again and again, does without.
  bool seed_with_usual = true;
  // Looking ahead: with targets, the greedy designs up to them under each criterion are
  // revisited this many times and the soonest kept (src/plan/refine.h); 0: the greedy
  // plan under `criterion` as it is.
  int refine_passes = 3;
  bool IsValid(const System& sys, std::string* error) const;
};

// Where a motion planned or evaluated with `o` in `ws` starts.
Eigen::Vector3d StartPose(const Workspace& ws, const PlanOptions& o);

// Fills o's limits and targets from name=value maps, as `kincal plan --limits/--targets`
// and kincald's guidance section give them: <control>=max |u|, accel=.. (every channel,
// units per second), accel_<control>=.., curvature=.. (1/m); <parameter>=target sigma (the
// parameters named are the ones scored). An error names the key and what was expected.
Status PlanLimitsFrom(const System& sys, const std::map<std::string, double>& limits,
                      const std::map<std::string, double>& targets, PlanOptions* o);

// Model parameters held at a known value (`kincal plan --fix`, kincald's robot.fixed): the
// design point takes the values, the prior knows them (sigma kHeldSigmaFraction of the
// parameter's default sigma, uncorrelated), and they are not scored (o->care: the others).
// An unknown name, or holding every parameter of the model, is an error naming the
// model's parameters.
inline constexpr double kHeldSigmaFraction = 1e-6;
Status HoldParameters(const System& sys, const std::map<std::string, double>& fixed,
                      Eigen::VectorXd* params, Eigen::MatrixXd* prior_cov, PlanOptions* o);

// The prior's sigma of named parameters (`kincal plan --prior`), over what `prior_cov`
// held: each named parameter's variance is set and its correlations with the others
// dropped. An unknown name, or a sigma not finite and positive, is an error naming the
// system's parameters.
Status SetPriorSigma(const System& sys, const std::map<std::string, double>& sigma,
                     Eigen::MatrixXd* prior_cov);

// Predicted sigma of every parameter against driving time.
struct SigmaCurve {
  std::vector<double> t_s;
  std::vector<Eigen::VectorXd> sigma;
  // First time every cared-for target is met; when the curve never meets them,
  // extrapolated from its end by sigma ~ t^-1/2 and `extrapolated` set. NaN without targets.
  double time_to_target_s = 0.0;
  bool extrapolated = false;
};

// A robot within the prior (the design point, or one at +-PlanOptions::prior_sigmas along
// an axis of the prior): when the quickest usual motion and the plan reach the targets
// there.
struct PriorRobotTimes {
  std::string robot;  // "the design point", "r_l -3 sigma", "prior axis 2 +3 sigma"
  double usual_s = 0.0;
  double plan_s = 0.0;  // infinity: not within the duration
};

struct Motion {
  std::string name;
  ControlSignal controls;                // from t = 0 on the signal's origin
  std::vector<double> segment_starts_s;  // a new free start pose at each (at least 0)
  SigmaCurve curve;
  std::vector<Eigen::Vector3d> path;  // measured target pose at the curve's times (nominal)
  bool stays_in = true;               // at the design point
  // Every robot within the prior keeps its target inside too (EveryRobotStaysIn; the
  // plan's own guarantee, and what a usual motion is kept for).
  bool every_robot_stays_in = true;
  double left_at_s = -1.0;  // first time it left the workspace (nominal), or -1
  // A usual motion stopped once it reaches the targets at the design point (what
  // every_robot_stays_in was judged on): the whole motion, which a robot that needs longer
  // drives on. Empty for the others.
  ControlSignal unstopped;
  // The plan's only (with targets and seed_with_usual): the plan driven by the robots
  // within the prior, against the quickest usual motion at each (src/plan/within_prior.h).
  std::vector<PriorRobotTimes> within_prior;
};

// The plan's speed-up over the quickest usual motion at that robot: usual_s / plan_s, 0
// when the plan does not reach the targets there within the duration.
double SpeedUp(const PriorRobotTimes& t);

// The least SpeedUp among a plan's within_prior (the first, on a tie), and the robot's
// name; (0, "") when it has none.
std::pair<double, std::string> LeastSpeedUp(const Motion& plan);

// The plan, with its sigma curve (EvaluateMotion every kCurveStepS). `params` and
// `prior_cov` are the design point and its uncertainty. The controls end with a stop at
// the acceleration limits and are at rest by duration_s (the last segment ends early
// enough for a stop from the speed limits); their last sample is at duration_s.
// With o.seed_with_usual, `usual` (when given) receives the usual motions compared with.
Status PlanMotion(const System& sys, const Eigen::VectorXd& params,
                  const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                  Motion* plan, std::vector<Motion>* usual = nullptr);

// How good an evaluated motion is, smaller better: its time to the targets, or without
// targets the scaled variance left at its end (the sum over the scored parameters of
// (sigma / prior sigma)^2).
double MotionRank(const Motion& m, const PlanOptions& o, const Eigen::VectorXd& prior_sigma);

// When an evaluated motion reaches the targets, or infinity (not within its curve, or
// only by extrapolation).
double ReachedAt(const Motion& m);

// Whether the prior's corner robots (the design point and the robots at +-prior_sigmas
// along each principal axis of the prior) keep their targets inside `ws` along controls
// `u` from the start pose, checked every 0.05 s to u's last sample. (The planner's own
// rule is stricter: it also checks the poses between them, pushed a fifth further out.)
bool EveryRobotStaysIn(const System& sys, const Eigen::VectorXd& params,
                       const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                       const ControlSignal& u);

// The usual calibration motions on the same time budget, speeds and workspace, each the
// best of its family (src/plan/family_search.h): a square, a circle each way and a
// figure-eight, each tried at sizes from the robot's scale to the workspace's and four
// speeds up to the limits, then finer about the best: the best (MotionRank) that keeps
// every robot within the prior inside, as the plan does, whole or stopped once it reaches
// the targets (`unstopped` then keeps the whole), and before it, when better, the best
// that stays in at the design point only (every_robot_stays_in false); and the thesis's 99
// constant-control runs (each a separate segment, the robot carried back between them). Each is
// evaluated like the plan.
std::vector<Motion> UsualMotions(const System& sys, const Eigen::VectorXd& params,
                                 const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                 const PlanOptions& o);

// Resolution of the sigma curves `kincal plan` reports (s).
inline constexpr double kCurveStepS = 0.25;

// Evaluates a motion's sigma curve (every `step_s`) and whether it stays in.
void EvaluateMotion(const System& sys, const Eigen::VectorXd& params,
                    const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                    double step_s, Motion* m);

// The candidate controls: a grid of `levels` values over each channel's limits (without
// those beyond the curvature limit at `params`).
std::vector<ControlSignal::Values> CandidateControls(const System& sys,
                                                     const Eigen::VectorXd& params,
                                                     const PlanOptions& o);

// The parameters scored: o.care, or all `num_params` when it is empty.
std::vector<int> ScoredParams(const PlanOptions& o, int num_params);

// Scaled score of a covariance (smaller is better).
double DesignScore(const Eigen::MatrixXd& cov, const Eigen::VectorXd& prior_sigma,
                   const PlanOptions& o);

}  // namespace kincal
