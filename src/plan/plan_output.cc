#include "kincal/plan/plan_output.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <kincal/controls_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "kincal/io/output_file.h"

namespace kincal {
namespace {

nlohmann::json CurveJson(const Motion& m) {
  nlohmann::json j;
  j["name"] = m.name;
  j["t_s"] = m.curve.t_s;
  std::vector<std::vector<double>> sigma;
  for (const auto& s : m.curve.sigma) sigma.emplace_back(s.data(), s.data() + s.size());
  j["sigma"] = sigma;
  j["time_to_target_s"] = std::isfinite(m.curve.time_to_target_s)
                              ? nlohmann::json(m.curve.time_to_target_s)
                              : nlohmann::json();
  j["extrapolated"] = m.curve.extrapolated;
  j["stays_in"] = m.stays_in;
  j["every_robot_stays_in"] = m.every_robot_stays_in;
  j["left_at_s"] = m.left_at_s;
  j["segments"] = m.segment_starts_s.size();
  std::vector<std::vector<double>> path;
  for (const auto& q : m.path) path.push_back({q.x(), q.y(), q.z()});
  j["path"] = path;
  return j;
}

// One line on the plan for the robots within the prior: its least and largest speed-up
// over the quickest usual motion there, and where it is least.
void PrintWithinPrior(const Motion& plan, const PlanOptions& o, std::ostream& out) {
  if (plan.within_prior.empty()) return;
  const auto [least, at] = LeastSpeedUp(plan);
  double most = 0.0;
  const PriorRobotTimes* worst = nullptr;
  for (const PriorRobotTimes& t : plan.within_prior) {
    most = std::max(most, SpeedUp(t));
    if (t.robot == at) worst = &t;
  }
  out << std::setprecision(3) << "for the robots at +-" << o.prior_sigmas
      << " sigma along the prior's axes (plan.json: within_prior): the plan is " << least << "x to "
      << most << "x as fast as the quickest usual motion there; least at " << at << " (the plan ";
  if (std::isfinite(worst->plan_s)) {
    out << worst->plan_s << " s";
  } else {
    out << "not within " << o.duration_s << " s";
  }
  out << ", the usual motion " << worst->usual_s << " s)\n";
}

}  // namespace

std::string ControlsCsv(const System& sys, const ControlSignal& u) {
  std::ostringstream out;
  out << "t";
  for (const auto& c : sys.model().controls()) out << "," << c.name;
  out << "\n" << std::setprecision(10);
  for (size_t i = 0; i < u.size(); ++i) {
    out << u.TimeAt(static_cast<int>(i));
    for (int c = 0; c < sys.num_controls(); ++c)
      out << "," << u.ValuesAt(static_cast<int>(i))[static_cast<size_t>(c)];
    out << "\n";
  }
  return out.str();
}

Status WritePlanFiles(const std::string& dir, const System& sys, const Eigen::VectorXd& params,
                      const Eigen::MatrixXd& prior_cov, const PlanOptions& o, const Motion& plan,
                      const std::vector<Motion>& usual) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::Error(dir + ": cannot create the output directory: " + ec.message());
  nlohmann::json j;
  j["model"] = sys.model().name();
  std::vector<std::string> names, units;
  for (const auto& p : sys.params()) names.push_back(p.name), units.push_back(p.unit);
  j["params"] = names;
  j["units"] = units;
  j["design_point"] = std::vector<double>(params.data(), params.data() + params.size());
  const Eigen::VectorXd s0 = prior_cov.diagonal().cwiseSqrt();
  j["prior_sigma"] = std::vector<double>(s0.data(), s0.data() + s0.size());
  std::vector<double> targets(static_cast<size_t>(sys.num_params()), 0.0);
  for (int i = 0; i < o.targets.size(); ++i) targets[static_cast<size_t>(i)] = o.targets[i];
  j["targets"] = targets;
  j["care"] = o.care;
  j["duration_s"] = o.duration_s;
  j["criterion"] = o.criterion == DesignCriterion::kA   ? "A"
                   : o.criterion == DesignCriterion::kD ? "D"
                                                        : "targets";
  j["pose_sigma"] = {o.info.pose_sigma.x(), o.info.pose_sigma.y(), o.info.pose_sigma.z()};
  j["pose_rate_hz"] = o.info.pose_rate_hz;
  j["plan"] = CurveJson(plan);
  // The plan driven by the robots within the prior, against the quickest usual motion there.
  j["within_prior"] = nlohmann::json::array();
  for (const PriorRobotTimes& t : plan.within_prior) {
    j["within_prior"].push_back(
        {{"robot", t.robot},
         {"usual_s", t.usual_s},
         {"plan_s", std::isfinite(t.plan_s) ? nlohmann::json(t.plan_s) : nlohmann::json()},
         {"speedup", SpeedUp(t)}});
  }
  j["usual"] = nlohmann::json::array();
  for (const auto& m : usual) j["usual"].push_back(CurveJson(m));
  if (Status s = WriteFileAtomically(dir + "/plan.csv", ControlsCsv(sys, plan.controls), "plan");
      !s.ok()) {
    return s;
  }
  return WriteFileAtomically(dir + "/plan.json", j.dump(1) + "\n", "plan");
}

void PrintPlanSummary(const System& sys, const PlanOptions& o, const Motion& plan,
                      const std::vector<Motion>& usual, std::ostream& out) {
  out << "predicted sigma after " << o.duration_s << " s";
  if (o.targets.size() > 0) out << " and time to the targets";
  std::vector<const Motion*> all = {&plan};
  for (const auto& m : usual) all.push_back(&m);
  // Columns as wide as the longest parameter name, and a space between them.
  int width = 12;
  for (const auto& p : sys.params()) width = std::max(width, static_cast<int>(p.name.size()) + 1);
  int name_width = 18;
  for (const Motion* m : all)
    name_width = std::max(name_width, static_cast<int>(m->name.size()) + 2);
  out << ":\n" << std::left << std::setw(name_width) << "motion";
  for (const auto& p : sys.params()) out << std::setw(width) << p.name;
  out << "time to target\n";
  for (const Motion* m : all) {
    out << std::setw(name_width) << m->name;
    for (int i = 0; i < sys.num_params(); ++i)
      out << std::setw(width) << std::setprecision(3) << m->curve.sigma.back()[i];
    if (std::isfinite(m->curve.time_to_target_s)) {
      out << (m->curve.extrapolated ? "~" : "") << std::setprecision(4) << m->curve.time_to_target_s
          << " s" << (m->curve.extrapolated ? " (extrapolated)" : "");
    } else {
      out << "-";
    }
    if (!m->stays_in) {
      out << "  leaves the workspace at " << m->left_at_s << " s";
    } else if (!m->every_robot_stays_in) {
      out << "  leaves the workspace for a robot within the prior";
    }
    out << "\n";
  }
  PrintWithinPrior(plan, o, out);
}

Status PublishPlan(const System& sys, const Motion& plan, const std::string& channel) {
  lcm::LCM lcm;
  if (!lcm.good())
    return Status::Error("--publish: LCM could not be initialised (check LCM_DEFAULT_URL)");
  kincal::controls_t m{};
  m.schema_version = 1;
  m.model = std::string(sys.model().name());
  m.num_controls = sys.num_controls();
  for (const auto& c : sys.model().controls()) m.names.push_back(c.name);
  m.values.assign(static_cast<size_t>(m.num_controls), 0.0);
  const auto start = std::chrono::steady_clock::now();
  const auto wall0 = std::chrono::system_clock::now();
  for (size_t i = 0; i < plan.controls.size(); ++i) {
    const double t = plan.controls.TimeAt(static_cast<int>(i));
    const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(t));
    std::this_thread::sleep_until(due);
    for (int c = 0; c < m.num_controls; ++c)
      m.values[static_cast<size_t>(c)] =
          plan.controls.ValuesAt(static_cast<int>(i))[static_cast<size_t>(c)];
    const auto wall = wall0 + std::chrono::duration_cast<std::chrono::system_clock::duration>(
                                  std::chrono::duration<double>(t));
    m.utime = m.sender_utime =
        std::chrono::duration_cast<std::chrono::microseconds>(wall.time_since_epoch()).count();
    if (lcm.publish(channel, &m) != 0)
      return Status::Error("--publish: LCM publish on " + channel + " failed");
  }
  return Status{};
}

}  // namespace kincal
