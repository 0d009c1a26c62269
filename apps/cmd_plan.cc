// kincal plan: how to drive a robot to calibrate it fastest, against the usual motions.
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "kincal/analysis/analyze.h"
#include "kincal/analysis/option_lists.h"
#include "kincal/io/checkpoint.h"
#include "kincal/plan/advice.h"
#include "kincal/plan/plan_output.h"
#include "kincal/plan/planner.h"
#include "kincal/sim/scenario.h"
#include "kincal/vision/camera.h"
#include "kincal/vision/setup_files.h"
#include "options.h"
#include "python_scripts.h"

namespace kincal::app {
namespace {

struct PlanArgs {
  std::string model, effects, init, prior, checkpoint, report, camera, floor, target, arena,
      pose_sigma, limits, targets, care, fix, criterion = "targets", out;
  double pose_rate_hz = 15.0, duration_s = 60.0, rate_hz = 20.0, segment_s = 0.5,
         target_height_m = 0.1, margin_px = 10.0;
  bool publish = false, no_plot = false, advise = false;
  double horizon_s = 3.0;
  std::string channel = "KINCAL_CONTROLS";
};

StatusOr<std::vector<double>> ParseNumbers(const std::string& text, size_t n, const char* what) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x)) {
      return Status::Error(std::string(what) + ": '" + item + "' is not a number");
    }
    v.push_back(x);
  }
  if (v.size() != n) {
    return Status::Error(std::string(what) + ": " + std::to_string(n) +
                         " comma-separated numbers expected, got '" + text + "'");
  }
  return v;
}

StatusOr<std::map<std::string, double>> ParseMap(const std::string& text, const char* what) {
  std::map<std::string, double> m;
  KINCAL_RETURN_IF_ERROR(ParseInitList(text, &m, what));
  return m;
}

// The design point and prior: --init values over the model's defaults (prior: the
// defaults' sigma), or a checkpoint's or report's estimate and covariance.
Status DesignPoint(const System& sys, const PlanArgs& a, Eigen::VectorXd* p, Eigen::MatrixXd* c) {
  const int n = sys.num_params();
  KINCAL_ASSIGN_OR_RETURN(const auto init, ParseMap(a.init, "--init"));
  KINCAL_ASSIGN_OR_RETURN(*p, ParamsFrom(sys, init, "--init"));
  *c = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    c->diagonal()[i] = std::pow(sys.params()[static_cast<size_t>(i)].default_sigma, 2);
  if (a.checkpoint.empty() && a.report.empty()) return Status();
  const std::string& source = a.checkpoint.empty() ? a.report : a.checkpoint;
  KINCAL_ASSIGN_OR_RETURN(const Checkpoint ck, a.checkpoint.empty()
                                                   ? ReadReportAsCheckpoint(a.report)
                                                   : ReadCheckpoint(a.checkpoint));
  const std::vector<std::string>& names = ck.names;
  std::vector<int> at(names.size(), -1);
  for (size_t k = 0; k < names.size(); ++k) {
    at[k] = sys.ParamIndex(names[k]);
    if (at[k] < 0) {
      return Status::Error(source + ": parameter '" + names[k] + "' is not one of the " +
                           std::string(sys.model().name()) + " system's");
    }
    (*p)[at[k]] = ck.values[k];
  }
  for (size_t k = 0; k < names.size(); ++k) {
    for (size_t l = 0; l < names.size(); ++l)
      (*c)(at[k], at[l]) = ck.covariance(static_cast<int>(k), static_cast<int>(l));
  }
  return Status();
}

StatusOr<std::unique_ptr<Workspace>> WorkspaceFrom(const PlanArgs& a) {
  if (!a.arena.empty()) {
    KINCAL_ASSIGN_OR_RETURN(const auto v, ParseNumbers(a.arena, 4, "--arena X0,Y0,X1,Y1"));
    if (!(v[0] < v[2] && v[1] < v[3]))
      return Status::Error("--arena: X0 < X1 and Y0 < Y1 expected");
    return MakeArena(v[0], v[1], v[2], v[3]);
  }
  if (a.camera.empty() || a.floor.empty()) {
    return Status::Error("a workspace is needed: --arena X0,Y0,X1,Y1, or --camera and --floor");
  }
  KINCAL_ASSIGN_OR_RETURN(const auto camera, vision::ReadCameraYaml(a.camera));
  KINCAL_ASSIGN_OR_RETURN(const auto floor, vision::ReadFloorYaml(a.floor));
  KINCAL_ASSIGN_OR_RETURN(const auto target, vision::ReadTargetLayoutYaml(a.target));
  return MakeCameraView(camera, floor, target, a.target_height_m, a.margin_px);
}

StatusOr<PlanOptions> OptionsFrom(const System& sys, const PlanArgs& a) {
  std::ostringstream segment;
  if (a.segment_s > a.duration_s) {
    segment << "--segment " << a.segment_s << " s is longer than --duration " << a.duration_s
            << " s";
  } else if (a.segment_s * a.rate_hz < 1.0) {
    segment << "--segment " << a.segment_s
            << " s is shorter than one control period (1/--rate: " << 1.0 / a.rate_hz << " s)";
  }
  if (!segment.str().empty()) return Status::Error(segment.str());
  PlanOptions o;
  o.duration_s = a.duration_s;
  o.control_rate_hz = a.rate_hz;
  o.segment_s = a.segment_s;
  o.info.pose_rate_hz = a.pose_rate_hz;
  if (!a.pose_sigma.empty()) {
    KINCAL_ASSIGN_OR_RETURN(const auto s,
                            ParseNumbers(a.pose_sigma, 3, "--pose-sigma SX,SY,STHETA"));
    o.info.pose_sigma = Eigen::Vector3d(s[0], s[1], s[2]);
  }
  KINCAL_ASSIGN_OR_RETURN(const auto limits, ParseMap(a.limits, "--limits"));
  KINCAL_ASSIGN_OR_RETURN(const auto targets, ParseMap(a.targets, "--targets"));
  if (const Status s = PlanLimitsFrom(sys, limits, targets, &o); !s.ok()) {
    return Status::Error("--" + s.message());
  }
  if (a.criterion == "a") {
    o.criterion = DesignCriterion::kA;
  } else if (a.criterion == "d") {
    o.criterion = DesignCriterion::kD;
  } else if (a.criterion == "targets") {
    o.criterion = DesignCriterion::kTargets;
  } else {
    return Status::Error("--criterion: a, d or targets expected, not '" + a.criterion + "'");
  }
  std::string error;
  if (!o.IsValid(sys, &error)) return Status::Error(error);
  return o;
}

// --advise: what to drive next from the estimate, and the time to the targets.
StatusOr<int> RunAdvice(const System& sys, const Eigen::VectorXd& p, const Eigen::MatrixXd& cov,
                        const PlanOptions& o, const PlanArgs& a) {
  Advice adv;
  KINCAL_RETURN_IF_ERROR(Advise(sys, p, cov, o, a.horizon_s, &adv));
  const auto& info = sys.params()[static_cast<size_t>(adv.worst)];
  std::cout << "least determined: " << info.name << " (sigma " << adv.sigma_now[adv.worst] << " "
            << info.unit << ", " << adv.worst_ratio << " x its target)\n"
            << "next: " << adv.motion << " (sigma of " << info.name << " then "
            << adv.sigma_after[adv.worst] << ")\n";
  if (std::isfinite(adv.time_to_target_s)) {
    std::cout << "predicted driving time to every target: " << adv.time_to_target_s << " s\n";
  } else if (o.targets.size() > 0) {
    std::cout << "predicted driving time to every target: more than 10 minutes\n";
  }
  nlohmann::json j;
  j["parameter"] = info.name;
  j["sigma"] = adv.sigma_now[adv.worst];
  j["ratio_to_target"] = adv.worst_ratio;
  j["motion"] = adv.motion;
  j["controls"] =
      std::vector<double>(adv.controls.begin(), adv.controls.begin() + sys.num_controls());
  j["duration_s"] = adv.duration_s;
  j["twist"] = {adv.twist.x(), adv.twist.y()};
  j["time_to_target_s"] =
      std::isfinite(adv.time_to_target_s) ? nlohmann::json(adv.time_to_target_s) : nlohmann::json();
  std::vector<std::string> names;
  for (const auto& pi : sys.params()) names.push_back(pi.name);
  j["params"] = names;
  j["sigma_now"] =
      std::vector<double>(adv.sigma_now.data(), adv.sigma_now.data() + adv.sigma_now.size());
  j["sigma_after"] =
      std::vector<double>(adv.sigma_after.data(), adv.sigma_after.data() + adv.sigma_after.size());
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) return Status::Error(a.out + ": cannot create the output directory: " + ec.message());
  KINCAL_RETURN_IF_ERROR(WriteOutput(a.out + "/advice.json", j.dump(1) + "\n", "advice"));
  return 0;
}

// The system, design point, prior and options the command line describes.
Status SetUp(const PlanArgs& a, std::unique_ptr<System>* sys, Eigen::VectorXd* p,
             Eigen::MatrixXd* prior, PlanOptions* o) {
  if (!a.checkpoint.empty() && !a.report.empty()) {
    return Status::Error("--checkpoint and --report: one prior at most");
  }
  if (!a.arena.empty() && (!a.camera.empty() || !a.floor.empty())) {
    return Status::Error("--arena, or --camera with --floor: one workspace");
  }
  std::vector<std::string> effects;
  if (const Status s = ParseEffectList(a.effects, &effects); !s.ok())
    return Status::Error("--effects: " + s.message());
  KINCAL_RETURN_IF_ERROR(MakeSystem(a.model, effects, {}, sys));
  KINCAL_RETURN_IF_ERROR(DesignPoint(**sys, a, p, prior));
  KINCAL_ASSIGN_OR_RETURN(const auto prior_sigma, ParseMap(a.prior, "--prior"));
  if (const Status s = SetPriorSigma(**sys, prior_sigma, prior); !s.ok())
    return Status::Error("--" + s.message());
  KINCAL_ASSIGN_OR_RETURN(*o, OptionsFrom(**sys, a));
  KINCAL_ASSIGN_OR_RETURN(const auto fixed, ParseMap(a.fix, "--fix"));
  if (const Status s = HoldParameters(**sys, fixed, p, prior, o); !s.ok())
    return Status::Error("--" + s.message());
  return Status();
}

StatusOr<int> Run(const PlanArgs& a) {
  std::unique_ptr<System> sys;
  Eigen::VectorXd p;
  Eigen::MatrixXd prior;
  PlanOptions o;
  KINCAL_RETURN_IF_ERROR(SetUp(a, &sys, &p, &prior, &o));
  KINCAL_RETURN_IF_ERROR(CheckOutputFolder(a.out, "plan"));
  if (a.advise) return RunAdvice(*sys, p, prior, o, a);
  KINCAL_ASSIGN_OR_RETURN(const auto ws, WorkspaceFrom(a));
  std::cerr << "kincal plan: " << a.duration_s << " s in the " << ws->Describe() << "\n";
  Motion plan;
  std::vector<Motion> usual;
  KINCAL_RETURN_IF_ERROR(PlanMotion(*sys, p, prior, *ws, o, &plan, &usual));
  PrintPlanSummary(*sys, o, plan, usual, std::cout);
  KINCAL_RETURN_IF_ERROR(WritePlanFiles(a.out, *sys, p, prior, o, plan, usual));
  if (!a.no_plot) {
    SetLcmTypesPath();
    const std::string err = RunAndWait({PythonInterpreter(), PythonScript("plot_plan.py", nullptr),
                                        a.out + "/plan.json", a.out + "/plan.png"});
    if (!err.empty()) {
      return Status::Error("plan.png: " + err +
                           " (plan.csv and plan.json are written; --no-plot skips the plot)");
    }
  }
  if (a.publish) KINCAL_RETURN_IF_ERROR(PublishPlan(*sys, plan, a.channel));
  return 0;
}

}  // namespace

Command AddPlan(CLI::App& app) {
  auto a = std::make_shared<PlanArgs>();
  app.add_option("--model", a->model, "kinematic model")->required();
  app.add_option("--effects", a->effects, "declared effects, e.g. actuator_lag,time_offset");
  app.add_option("--init", a->init, "design point, name=value,... (prior: the generic sigma)");
  app.add_option("--prior", a->prior,
                 "the prior's sigma of named parameters, name=sigma,... (over the generic sigma "
                 "or the checkpoint's)");
  app.add_option("--fix", a->fix, "model parameters known (held, not planned for), name=value,...");
  app.add_option("--checkpoint", a->checkpoint,
                 "a kincald checkpoint: design point and covariance");
  app.add_option("--report", a->report, "an analyze report.json: design point and sigma");
  app.add_option("--camera", a->camera, "camera intrinsics (OpenCV or ROS camera_info YAML)");
  app.add_option("--floor", a->floor, "floor extrinsics (kincal floorcal)");
  app.add_option("--target", a->target, "target layout YAML (default: the thesis plate)");
  app.add_option("--target-height", a->target_height_m, "target plane above the floor, m");
  app.add_option("--margin", a->margin_px, "markers stay this far inside the frame, px");
  app.add_option("--arena", a->arena, "workspace X0,Y0,X1,Y1 on the floor, m");
  app.add_option("--pose-sigma", a->pose_sigma, "pose noise SX,SY,STHETA (m, m, rad)");
  app.add_option("--pose-rate", a->pose_rate_hz, "poses per second")
      ->check(AboveAndAtMost(0.0, kMaxDesignPoseRateHz));
  app.add_option("--duration", a->duration_s, "driving time, s")
      ->check(AboveAndAtMost(0.0, kMaxPlanDurationS));
  app.add_option("--limits", a->limits,
                 "<control>=max|..|, accel=.. (units/s), accel_<control>=.., curvature=.. (1/m)")
      ->required();
  app.add_option("--rate", a->rate_hz, "control samples per second")
      ->check(Between(1.0, kMaxPlanControlRateHz));
  app.add_option("--segment", a->segment_s, "seconds per planning decision")->check(AboveZero());
  app.add_option("--targets", a->targets,
                 "target sigma, name=value,...: the parameters scored and timed (default: all, "
                 "scaled by their prior sigma)");
  app.add_option("--criterion", a->criterion,
                 "targets (the default: sum of squared scaled variances), a (their sum) or d "
                 "(log det); scaled by --targets, else by the prior sigma");
  app.add_option("--out", a->out, "output directory (plan.csv, plan.json, plan.png)")->required();
  app.add_flag("--no-plot", a->no_plot, "skip plan.png");
  app.add_flag("--publish", a->publish, "play the plan as kincal.controls_t on LCM, in real time");
  app.add_flag("--advise", a->advise,
               "instead of a plan: the least determined parameter, the motion to drive next "
               "and the time to the targets (DIR/advice.json)");
  app.add_option("--horizon", a->horizon_s, "--advise: seconds the advised motion is held");
  app.add_option("--channel", a->channel, "LCM channel for --publish");
  return [a]() -> StatusOr<int> { return Run(*a); };
}

}  // namespace kincal::app
