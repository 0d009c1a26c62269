// The motions people calibrate with today, drawn to the workspace and the limits, and the
// evaluation every motion (the plan too) gets.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "kincal/plan/planner.h"
#include "kincal/sim/thesis.h"
#include "plan/family_search.h"
#include "plan/shaping.h"

namespace kincal {
namespace {

using plan_internal::Values;

constexpr double kHeadroom = 0.7;  // of each limit, left for turning and slewing

// A twist schedule: (v, omega, duration) pieces; each piece is reached by slewing.
struct Piece {
  double v, omega, seconds;
};

// The options with every limit cut to `headroom` of it.
PlanOptions WithHeadroom(const PlanOptions& o, double headroom = kHeadroom) {
  PlanOptions tight = o;
  for (double& m : tight.max_abs) m *= headroom;
  return tight;
}

// The largest x in [lo, hi] for which `fits(x)` holds, by bisection (`fits` true at lo).
template <class Fits>
double LargestFitting(double lo, double hi, int iterations, Fits fits) {
  for (int it = 0; it < iterations; ++it) {
    const double x = 0.5 * (lo + hi);
    (fits(x) ? lo : hi) = x;
  }
  return lo;
}

// Whether twist (v, omega) has controls within the headroom of the limits.
bool Drivable(const System& sys, const Eigen::VectorXd& p, const PlanOptions& tight, double v,
              double omega) {
  Values u{};
  return plan_internal::TwistToControls(sys, p, v, omega, tight, &u);
}

// Fastest forward speed whose controls (and those of turning at radius r) fit within the
// headroom of the limits.
double CruiseSpeed(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o, double radius,
                   double headroom = kHeadroom) {
  const PlanOptions tight = WithHeadroom(o, headroom);
  return LargestFitting(0.0, 10.0, 50, [&](double v) {
    return Drivable(sys, p, tight, v, radius > 0.0 ? v / radius : 0.0);
  });
}

// Fastest turn in place within the headroom, 0 when the robot cannot turn in place.
double SpinRate(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o,
                double headroom = kHeadroom) {
  if (o.max_curvature > 0.0) return 0.0;
  const PlanOptions tight = WithHeadroom(o, headroom);
  const double w =
      LargestFitting(0.0, 50.0, 50, [&](double w) { return Drivable(sys, p, tight, 0.0, w); });
  return w > 1e-3 ? w : 0.0;
}

// The tightest turn within the headroom at a tenth of the straight cruise speed (a
// steered robot's steering limit); 0 when it turns in place.
double MinTurnRadius(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o,
                     double straight_speed) {
  const PlanOptions tight = WithHeadroom(o);
  const double v = 0.1 * straight_speed;
  const double k =  // curvature, 1/m
      LargestFitting(0.0, 1e3, 60, [&](double k) { return Drivable(sys, p, tight, v, v * k); });
  // A tenth wider: at the steering limit itself the controls of faster turns are found
  // only at the edge of the box.
  return k >= 999.0 ? 0.0 : 1.1 / std::max(k, 1e-9);
}

std::optional<Motion> FromPieces(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o,
                                 const std::string& name, const std::vector<Piece>& pieces) {
  // Pieces repeating faster than two control periods cannot be driven as drawn (at limits
  // of 10^9 rad/s, loops of a micrometre once made tens of millions of control samples).
  double cycle_s = 0.0;
  for (const Piece& piece : pieces) cycle_s += piece.seconds;
  if (!(cycle_s >= 2.0 / o.control_rate_hz)) return std::nullopt;
  Motion m;
  m.name = name;
  m.controls = ControlSignal(sys.num_controls(), 0);
  m.segment_starts_s = {0.0};
  Values now{};
  double t = 0.0;
  // Like the plan, at rest by duration_s: driving ends a stop from the limits before it.
  const double drive_s =
      std::max(0.0, o.duration_s - plan_internal::LongestStopSeconds(o, sys.num_controls()));
  for (size_t k = 0; t < drive_s - 1e-9; k = (k + 1) % pieces.size()) {
    Values to{};
    plan_internal::TwistToControls(sys, p, pieces[k].v, pieces[k].omega, o, &to);
    const double t1 = std::min(drive_s, t + pieces[k].seconds);
    plan_internal::AppendSlewed(&m.controls, t, t1, to, o, &now);
    t = t1;
  }
  plan_internal::AppendStopAndRest(&m.controls, t, o.duration_s, o, &now);
  return m;
}

// Seconds the channels need to slew from rest to the controls of twist (v, omega).
double RampTime(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o, double v,
                double omega) {
  Values u{};
  plan_internal::TwistToControls(sys, p, v, omega, o, &u);
  double t = 0.0;
  for (size_t c = 0; c < o.max_accel.size(); ++c) {
    if (o.max_accel[c] > 0.0) t = std::max(t, std::abs(u[c]) / o.max_accel[c]);
  }
  return t;
}

// Sides and corners with a stop between them: a straight ramp up and down integrates to
// the piece's full length, so the square closes (a lag only delays it).
std::vector<Piece> Square(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o,
                          double side, double v, double spin, double turn_radius) {
  const Piece edge{v, 0.0, side / v};
  const Piece corner = spin > 0.0
                           ? Piece{0.0, spin, 0.5 * std::numbers::pi / spin}
                           : Piece{v, v / turn_radius, 0.5 * std::numbers::pi * turn_radius / v};
  return {edge,
          {0.0, 0.0, RampTime(sys, p, o, edge.v, edge.omega)},
          corner,
          {0.0, 0.0, RampTime(sys, p, o, corner.v, corner.omega)}};
}

// The thesis's Table 6-4 runs as twists at its nominal robot, scaled so that the fastest
// fits, each a segment of equal length.
// Runs a robot cannot drive (tighter than its tightest turn) are left out, and the name
// says how many were kept.
Motion ThesisRuns(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o,
                  double min_radius) {
  Motion m;
  m.controls = ControlSignal(sys.num_controls(), 0);
  std::vector<Eigen::Vector2d> twists;
  for (const auto& w : kThesisControls) {
    const double v = 0.5 * (kThesisRL * w[0] + kThesisRR * w[1]);
    const double om = (kThesisRR * w[1] - kThesisRL * w[0]) / kThesisD;
    if (min_radius > 0.0 && std::abs(om) * min_radius > std::abs(v)) continue;
    twists.emplace_back(v, om);
  }
  m.name = twists.size() == 99 ? std::string("thesis 99 runs")
                               : "thesis runs (" + std::to_string(twists.size()) + " of 99)";
  if (twists.empty()) return m;
  // One common scale: the largest at which every run's controls fit the headroom.
  const PlanOptions tight = WithHeadroom(o);
  const double scale = LargestFitting(0.0, 1.0, 40, [&](double s) {
    return std::all_of(twists.begin(), twists.end(), [&](const Eigen::Vector2d& tw) {
      return Drivable(sys, p, tight, s * tw.x(), s * tw.y());
    });
  });
  const double each = o.duration_s / static_cast<double>(twists.size());
  Values now{};
  double t = 0.0;
  for (const auto& tw : twists) {
    Values to{};
    plan_internal::TwistToControls(sys, p, scale * tw.x(), scale * tw.y(), o, &to);
    m.segment_starts_s.push_back(t);
    now = Values{};  // each run starts at rest
    plan_internal::AppendSlewed(&m.controls, t, t + each, to, o, &now);
    t += each;
  }
  plan_internal::AppendRest(&m.controls, t);
  return m;
}

double TimeToTarget(const SigmaCurve& c, const Eigen::VectorXd& targets, const PlanOptions& o,
                    bool* extrapolated) {
  *extrapolated = false;
  if (targets.size() == 0 || c.t_s.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::vector<int> idx = ScoredParams(o, static_cast<int>(targets.size()));
  for (size_t k = 0; k < c.t_s.size(); ++k) {
    bool met = true;
    for (int i : idx) met = met && (!(targets[i] > 0.0) || c.sigma[k][i] <= targets[i]);
    if (met) return c.t_s[k];
  }
  *extrapolated = true;
  double worst = 1.0;
  for (int i : idx) {
    if (targets[i] > 0.0) worst = std::max(worst, std::pow(c.sigma.back()[i] / targets[i], 2));
  }
  return c.t_s.back() * worst;
}

// How each family is tried (BestOfFamily): sizes from the robot's own scale (the smallest
// square it can drive at speed, the loop it drives a third as fast as it drives straight)
// to the workspace's (a square's side up to 0.6 of its size, a loop's radius up to 0.3).
constexpr int kSquareSides = 5;
constexpr int kRadii = 13;
constexpr double kLargestSide = 0.6, kLargestRadius = 0.3;  // of the workspace's size

struct Family {
  const System& sys;
  const Eigen::VectorXd& p;
  const PlanOptions& o;
  double size, min_radius, spin;
  double drive_s;     // driving time: the duration less a stop from the limits
  double smallest_r;  // the smallest loop tried: at least the tightest turn
};

// The radius of the turn the robot drives a third as fast as it drives straight (at the
// limits), or its tightest turn when that is wider.
double SmallestLoop(const System& sys, const Eigen::VectorXd& p, const PlanOptions& o,
                    double min_radius) {
  const double straight = CruiseSpeed(sys, p, o, 0.0, 1.0);
  const double r = LargestFitting(0.0, 1e3, 50, [&](double x) {
    return CruiseSpeed(sys, p, o, 1e3 - x, 1.0) >= straight / 3.0;
  });
  return std::max(min_radius, 1e3 - r);
}

std::string Described(const std::string& family, const std::string& size, double v) {
  char text[96];
  std::snprintf(text, sizeof(text), "%s (%s, %.2f m/s)", family.c_str(), size.c_str(), v);
  return text;
}

std::string Metres(const char* what, double x) {
  char text[48];
  std::snprintf(text, sizeof(text), "%s %.2f m", what, x);
  return text;
}

// Squares of a side at a fraction of the fastest speed (corners: turns in place, or of a
// steered robot's tightest radius), and the sides tried: from ramping up to full speed and
// down again (and two corners) to the workspace's.
std::pair<plan_internal::FamilyMember, plan_internal::FamilySizes> Squares(const Family& f) {
  const double r = std::max(f.min_radius, 0.1 * f.size);
  const double fastest = CruiseSpeed(f.sys, f.p, f.o, f.spin > 0.0 ? 0.0 : r, 1.0);
  const double smallest =
      std::max(fastest * RampTime(f.sys, f.p, f.o, fastest, 0.0), 2.0 * f.smallest_r);
  return {[&f, r, fastest](double side, double k) -> std::optional<Motion> {
            const double v = k * fastest;
            if (!(v > 0.0)) return std::nullopt;  // the limits allow no motion of this kind
            return FromPieces(f.sys, f.p, f.o, Described("square", Metres("side", side), v),
                              Square(f.sys, f.p, f.o, side, v, k * f.spin, r));
          },
          {smallest, kLargestSide * f.size, kSquareSides}};
}

// Circles of a radius (at least the tightest turn), turning each way in turn: one lap each
// way a figure-eight, as many laps as fill half the driving time a circle each way.
plan_internal::FamilyMember Loops(const Family& f, const char* name, bool figure_eight) {
  return [&f, name, figure_eight](double r, double k) -> std::optional<Motion> {
    const double v = k * CruiseSpeed(f.sys, f.p, f.o, r, 1.0);
    const double loop = 2.0 * std::numbers::pi * r / v;
    // Not a full turn each way in the time (or no motion of this kind at all).
    if (!(v > 0.0) || r < f.min_radius || 2.0 * loop > f.drive_s) return std::nullopt;
    const int laps = figure_eight ? 1 : std::max(1, static_cast<int>(0.5 * f.drive_s / loop));
    return FromPieces(f.sys, f.p, f.o, Described(name, Metres("radius", r), v),
                      {{v, v / r, laps * loop}, {v, -v / r, laps * loop}});
  };
}

}  // namespace

double MotionRank(const Motion& m, const PlanOptions& o, const Eigen::VectorXd& prior_sigma) {
  if (std::isfinite(m.curve.time_to_target_s)) return m.curve.time_to_target_s;
  if (m.curve.sigma.empty()) return std::numeric_limits<double>::infinity();
  double left = 0.0;
  for (int i : ScoredParams(o, static_cast<int>(prior_sigma.size()))) {
    left += std::pow(m.curve.sigma.back()[i] / prior_sigma[i], 2);
  }
  return left;
}

double ReachedAt(const Motion& m) {
  const double t = m.curve.time_to_target_s;
  return std::isfinite(t) && !m.curve.extrapolated ? t : std::numeric_limits<double>::infinity();
}

std::vector<Motion> UsualMotions(const System& sys, const Eigen::VectorXd& params,
                                 const Eigen::MatrixXd& prior_cov, const Workspace& ws,
                                 const PlanOptions& o) {
  const double min_radius =
      std::max(o.max_curvature > 0.0 ? 1.0 / o.max_curvature : 0.0,
               MinTurnRadius(sys, params, o, CruiseSpeed(sys, params, o, 0.0)));
  const Family f{sys,
                 params,
                 o,
                 ws.Size(),
                 min_radius,
                 SpinRate(sys, params, o, 1.0),
                 o.duration_s - plan_internal::LongestStopSeconds(o, sys.num_controls()),
                 SmallestLoop(sys, params, o, min_radius)};
  std::vector<Motion> out;
  // Each family searched (drawn from the start at the workspace's centre, heading +x).
  const plan_internal::FamilySizes loops{f.smallest_r, kLargestRadius * f.size, kRadii};
  const std::array<std::pair<plan_internal::FamilyMember, plan_internal::FamilySizes>, 3> families =
      {{Squares(f),
        {Loops(f, "circle each way", false), loops},
        {Loops(f, "figure-eight", true), loops}}};
  for (const auto& [member, sizes] : families) {
    for (Motion& m : plan_internal::BestOfFamily(member, sizes, sys, params, prior_cov, ws, o)) {
      out.push_back(std::move(m));
    }
  }
  Motion runs = ThesisRuns(sys, params, o, min_radius);
  if (!runs.segment_starts_s.empty()) {
    EvaluateMotion(sys, params, prior_cov, ws, o, kCurveStepS, &runs);
    out.push_back(std::move(runs));
  }
  return out;
}

void EvaluateMotion(const System& sys, const Eigen::VectorXd& params,
                    const Eigen::MatrixXd& prior_cov, const Workspace& ws, const PlanOptions& o,
                    double step_s, Motion* m) {
  const Eigen::Vector3d start = StartPose(ws, o);
  DesignInformation info(sys, params, prior_cov, o.info);
  m->curve = SigmaCurve{};
  m->path.clear();
  m->stays_in = true;
  m->left_at_s = -1.0;
  std::vector<double> starts = m->segment_starts_s;
  if (starts.empty()) starts = {0.0};
  size_t next_start = 0;
  constexpr double kCheckS = 0.05;  // how often the target is checked to be inside
  double next_record = 0.0;
  for (double t = 0.0; t <= o.duration_s + 1e-9; t += kCheckS) {
    while (next_start < starts.size() && starts[next_start] <= t + 1e-9) {
      if (next_start > 0) info.Advance(starts[next_start], m->controls);
      info.StartSegment(start, starts[next_start], m->controls);
      ++next_start;
    }
    info.Advance(t, m->controls);
    if (m->stays_in && !ws.Contains(info.MeasuredPose())) {
      m->stays_in = false;
      m->left_at_s = t;
    }
    if (t >= next_record - 1e-9) {
      m->curve.t_s.push_back(t);
      m->curve.sigma.push_back(info.Covariance().diagonal().cwiseSqrt());
      m->path.push_back(info.MeasuredPose());
      next_record += step_s;
    }
  }
  m->curve.time_to_target_s = TimeToTarget(m->curve, o.targets, o, &m->curve.extrapolated);
}

}  // namespace kincal
