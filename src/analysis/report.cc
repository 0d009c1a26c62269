#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "kincal/analysis/analyze.h"
#include "kincal/io/output_file.h"

namespace kincal {
namespace {

using nlohmann::json;

json ParamsJson(const std::vector<ParamEstimate>& ps) {
  json j = json::object();
  for (const auto& p : ps) {
    j[p.name] = {
        {"value", p.value}, {"sigma", p.sigma}, {"sigma_white", p.sigma_model}, {"unit", p.unit}};
  }
  return j;
}

json FitJson(const FitReport& f) {
  json j;
  j["params"] = ParamsJson(f.params);
  j["effects"] = f.effects;
  j["fit"] = {{"pos_rms_m", f.fit.pos_rms_m},
              {"heading_rms_rad", f.fit.heading_rms_rad},
              {"windows", f.fit.windows}};
  j["heldout"] = {{"pos_rms_m", f.heldout.pos_rms_m},
                  {"heading_rms_rad", f.heldout.heading_rms_rad},
                  {"windows", f.heldout.windows}};
  j["cost"] = f.cost;
  j["fit_windows"] = f.fit_windows;
  j["unique"] = f.unique;
  if (!f.uniqueness.empty()) j["uniqueness"] = f.uniqueness;
  j["unobservable"] = f.unobservable;
  j["fixed"] = f.fixed;
  j["weakly_determined"] = f.weak;
  return j;
}

json DiagJson(const std::vector<DiagnosisTerm>& d, size_t top) {
  json j = json::array();
  for (size_t i = 0; i < d.size() && i < top; ++i) {
    j.push_back({{"component", d[i].component},
                 {"regressor", d[i].regressor},
                 {"r", d[i].r},
                 {"z", d[i].z}});
  }
  return j;
}

json TestsJson(const ResidualTests& t) {
  json j;
  const char* c[3] = {"along", "cross", "heading"};
  for (int i = 0; i < 3; ++i) {
    j[c[i]] = {{"bias_z", t.bias_z[i]},
               {"lag1_autocorr", t.lag1_autocorr[i]},
               {"ljung_box_p", t.ljung_box_p[i]}};
  }
  return j;
}

json DeadReckoningJson(const DeadReckoning& d) {
  return {{"duration_s", d.duration_s},
          {"rms_m", d.rms_m},
          {"final_m", d.final_m},
          {"final_rad", d.final_rad},
          {"runs", d.runs}};
}

json RunsJson(const std::vector<RunReport>& runs) {
  json j = json::array();
  for (const auto& r : runs) {
    j.push_back({{"index", r.index},
                 {"source", r.source},
                 {"heldout", r.heldout},
                 {"windows", r.windows},
                 {"before",
                  {{"pos_rms_m", r.before_pos_rms_m},
                   {"heading_rms_rad", r.before_heading_rms_rad},
                   {"dead_reckoning", DeadReckoningJson(r.dr_before)}}},
                 {"after",
                  {{"pos_rms_m", r.after_pos_rms_m},
                   {"heading_rms_rad", r.after_heading_rms_rad},
                   {"dead_reckoning", DeadReckoningJson(r.dr_after)}}}});
  }
  return j;
}

// The runs' table and the held-out dead reckoning, in the HTML page.
void RunsHtml(const AnalyzeResult& r, std::ostringstream& h) {
  h << "<h2>Dead reckoning over the held-out part</h2><p>Open loop from the first pose of "
    << "each held-out run through all of it (" << r.heldout_dr_after.runs << " run(s), "
    << r.heldout_dr_after.duration_s << " s), pooled RMS over runs:</p><table><tr><th></th>"
    << "<th>before</th><th>after</th></tr><tr><td>position RMS along the run [m]</td><td>"
    << r.heldout_dr_before.rms_m << "</td><td>" << r.heldout_dr_after.rms_m << "</td></tr>"
    << "<tr><td>final position error [m]</td><td>" << r.heldout_dr_before.final_m << "</td><td>"
    << r.heldout_dr_after.final_m << "</td></tr><tr><td>final heading error [rad]</td><td>"
    << r.heldout_dr_before.final_rad << "</td><td>" << r.heldout_dr_after.final_rad
    << "</td></tr></table>";
  if (r.runs.empty()) return;
  h << "<h2>Runs</h2><table><tr><th>run</th><th>part</th><th>windows</th><th>position RMS at "
    << r.horizon_s << " s [m] before</th><th>after</th><th>dead reckoning RMS [m] before</th>"
    << "<th>after</th><th>final [m] before</th><th>after</th><th>source</th></tr>";
  for (const auto& x : r.runs) {
    h << "<tr><td>" << x.index << "</td><td>" << (x.heldout ? "held out" : "fit") << "</td><td>"
      << x.windows << "</td><td>" << x.before_pos_rms_m << "</td><td>" << x.after_pos_rms_m
      << "</td><td>" << x.dr_before.rms_m << "</td><td>" << x.dr_after.rms_m << "</td><td>"
      << x.dr_before.final_m << "</td><td>" << x.dr_after.final_m << "</td><td>" << x.source
      << "</td></tr>";
  }
  h << "</table>";
}

// The title and what was fitted and held out, with the weights.
void HeaderHtml(const AnalyzeResult& r, std::ostringstream& h) {
  h << "<h1>kincal analysis: " << r.model << "</h1><p>" << r.source << "<br>";
  if (r.runs.empty()) {
    h << "fit span " << r.t_begin_s << " .. " << r.t_split_s << " s, held out " << r.t_split_s
      << " .. " << r.t_end_s << " s";
  } else {
    h << r.runs.size() << " runs, held out:";
    for (const auto& x : r.runs) {
      if (x.heldout) h << " " << x.index;
    }
  }
  h << "; horizon " << r.horizon_s << " s; residual weights: position " << r.pose_sigma[0] * 1e3
    << " mm, heading " << r.pose_sigma[1] * 1e3 << " mrad ("
    << (r.pose_sigma_estimated ? "estimated from the data" : "given") << ")</p>";
}

std::string Html(const AnalyzeResult& r) {
  std::ostringstream h;
  h << std::setprecision(4);
  h << "<!doctype html><html><head><meta charset='utf-8'><title>kincal analysis: " << r.model
    << "</title><style>body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
       "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:3px 8px;"
       "text-align:right}th{background:#eee}td:first-child{text-align:left}.acc{background:#dfd}"
       "img{max-width:100%}</style></head><body>";
  HeaderHtml(r, h);
  h << "<h2>Before and after</h2><table><tr><th></th><th>before</th><th>after</th></tr>";
  auto row = [&](const char* name, double a, double b) {
    h << "<tr><td>" << name << "</td><td>" << a << "</td><td>" << b << "</td></tr>";
  };
  row("fit position RMS [m]", r.before.fit.pos_rms_m, r.after.fit.pos_rms_m);
  row("fit heading RMS [rad]", r.before.fit.heading_rms_rad, r.after.fit.heading_rms_rad);
  row("held-out position RMS [m]", r.before.heldout.pos_rms_m, r.after.heldout.pos_rms_m);
  row("held-out heading RMS [rad]", r.before.heldout.heading_rms_rad,
      r.after.heldout.heading_rms_rad);
  h << "</table>";
  RunsHtml(r, h);
  h << "<p>Effects added: ";
  for (const auto& e : r.after.effects) h << "<b>" << e << "</b> ";
  if (r.after.effects.empty()) h << "none";
  h << "</p><h2>Parameters</h2><table><tr><th>parameter</th><th>before</th><th>after</th><th>unit</"
       "th></tr>";
  for (const auto& p : r.after.params) {
    h << "<tr><td>" << p.name << "</td><td>";
    for (const auto& q : r.before.params) {
      if (q.name == p.name) h << q.value << " ± " << q.sigma;
    }
    h << "</td><td>" << p.value << " ± " << p.sigma << "</td><td>" << p.unit << "</td></tr>";
  }
  h << "</table><p>σ: cluster-robust over prediction windows (1σ).";
  if (!r.after.fixed.empty()) {
    h << " Held at the given values (--fix), not fitted:";
    for (const auto& f : r.after.fixed) h << " <b>" << f << "</b>";
    h << ".";
  }
  h << "</p>";
  if (!r.after.weak.empty()) {
    h << "<p>Weakly determined:</p><ul>";
    for (const auto& w : r.after.weak) h << "<li>" << w << "</li>";
    h << "</ul>";
  }
  h << "<img src='residuals_time.png'><img src='residuals_vs.png'>";
  h << "<h2>Candidate effects</h2><table><tr><th>round</th><th>effect</th><th>held-out gain</th>"
       "<th>ΔBIC</th><th>parameters</th><th>evidence</th></tr>";
  for (const auto& t : r.trials) {
    h << "<tr" << (t.accepted ? " class='acc'" : "") << "><td>" << t.round << "</td><td>" << t.name
      << (t.accepted ? " ✔" : "") << "</td><td>" << t.heldout_gain << "</td><td>" << t.delta_bic
      << "</td><td>";
    for (const auto& p : t.params) h << p.name << "=" << p.value << "±" << p.sigma << " ";
    h << "</td><td style='text-align:left'>" << t.evidence << "</td></tr>";
  }
  h << "</table><h2>Diagnosis of the residual "
       "before</h2><table><tr><th>component</th><th>regressor</th><th>r</th><th>z</th></tr>";
  for (size_t i = 0; i < r.diagnosis_before.size() && i < 10; ++i) {
    const auto& t = r.diagnosis_before[i];
    h << "<tr><td>" << t.component << "</td><td>" << t.regressor << "</td><td>" << t.r
      << "</td><td>" << t.z << "</td></tr>";
  }
  h << "</table>";
  if (!r.warnings.empty()) {
    h << "<h2>Warnings</h2><ul>";
    for (const auto& w : r.warnings) h << "<li>" << w << "</li>";
    h << "</ul>";
  }
  h << "</body></html>\n";
  return h.str();
}

}  // namespace

Status WriteAnalysisReport(const AnalyzeResult& r, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::Error(dir + ": cannot create the report folder (" + ec.message() + ")");
  json j;
  j["model"] = r.model;
  j["source"] = r.source;
  j["before"] = FitJson(r.before);
  j["after"] = FitJson(r.after);
  json effects = json::array();
  for (const auto& t : r.trials) {
    effects.push_back({{"name", t.name},
                       {"round", t.round},
                       {"accepted", t.accepted},
                       {"params", ParamsJson(t.params)},
                       {"heldout_gain", t.heldout_gain},
                       {"combined_gain", t.combined_gain},
                       {"delta_bic", t.delta_bic},
                       {"signature_z", t.signature_z},
                       {"evidence", t.evidence}});
  }
  j["effects"] = effects;
  j["weights"] = {{"pos_sigma_m", r.pose_sigma[0]},
                  {"heading_sigma_rad", r.pose_sigma[1]},
                  {"estimated", r.pose_sigma_estimated},
                  {"note",
                   "residuals are weighted by 1/sigma^2 per component (x, y: pos_sigma_m; theta: "
                   "heading_sigma_rad)"}};
  j["span_s"] = {{"begin", r.t_begin_s}, {"split", r.t_split_s}, {"end", r.t_end_s}};
  j["runs"] = RunsJson(r.runs);
  j["dead_reckoning"] = {{"before", DeadReckoningJson(r.heldout_dr_before)},
                         {"after", DeadReckoningJson(r.heldout_dr_after)}};
  j["horizon_s"] = r.horizon_s;
  j["diagnosis"] = {{"before", DiagJson(r.diagnosis_before, 12)},
                    {"after", DiagJson(r.diagnosis_after, 12)}};
  j["tests"] = {{"before", TestsJson(r.tests_before)}, {"after", TestsJson(r.tests_after)}};
  j["goodness_of_fit"] = {{"model_heldout_m", r.goodness.model_m},
                          {"standstill_m", r.goodness.standstill_m},
                          {"constant_velocity_m", r.goodness.constant_velocity_m},
                          {"judged", r.goodness.judged},
                          {"explains_motion", r.goodness.explains},
                          {"verdict", r.goodness.verdict}};
  j["warnings"] = r.warnings;
  j["input"] = {{"control_rows", r.stats.control_rows},
                {"pose_rows", r.stats.pose_rows},
                {"control_repeated_times", r.stats.control_repeated_times},
                {"pose_repeated_times", r.stats.pose_repeated_times},
                {"pose_rows_lost", r.stats.pose_rows_lost}};
  std::ostringstream csv;
  csv << "step,t_s,heldout,along_m,cross_m,heading_rad\n" << std::setprecision(9);
  for (const auto& [step, pts] : r.residual_steps) {
    for (const auto& p : pts) {
      csv << step << "," << p.t_s << "," << (p.heldout ? 1 : 0) << "," << p.along << "," << p.cross
          << "," << p.heading << "\n";
    }
  }
  // The JSON last: a report.json in the folder means the whole report is there.
  if (Status s = WriteFileAtomically(dir + "/residuals.csv", csv.str(), "residuals"); !s.ok())
    return s;
  if (Status s = WriteFileAtomically(dir + "/report.html", Html(r), "report"); !s.ok()) return s;
  return WriteFileAtomically(dir + "/report.json", j.dump(2) + "\n", "report");
}

Status ReadReportEstimate(const std::string& path, ReportEstimate* out) {
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open for reading");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    return Status::Error(path + ": not JSON (" + e.what() + ")");
  }
  auto field = [&](const json& o, const char* key, json::value_t type) -> const json* {
    const auto it = o.find(key);
    return it != o.end() && it->type() == type ? &*it : nullptr;
  };
  const json* model = field(j, "model", json::value_t::string);
  const json* after = field(j, "after", json::value_t::object);
  const json* params = after ? field(*after, "params", json::value_t::object) : nullptr;
  const json* effects = after ? field(*after, "effects", json::value_t::array) : nullptr;
  if (!model || !params || !effects) {
    return Status::Error(path +
                         ": expected a kincal analyze report (model, after.params, "
                         "after.effects)");
  }
  ReportEstimate r;
  r.model = model->get<std::string>();
  if (const json* src = field(j, "source", json::value_t::string))
    r.source = src->get<std::string>();
  for (const auto& e : *effects) {
    if (!e.is_string()) return Status::Error(path + ": after.effects: expected names");
    r.effects.push_back(e.get<std::string>());
  }
  for (const auto& [name, p] : params->items()) {
    const auto v = p.find("value"), s = p.find("sigma");
    if (!p.is_object() || v == p.end() || s == p.end() || !v->is_number() || !s->is_number()) {
      return Status::Error(path + ": after.params." + name + ": expected {value, sigma, unit}");
    }
    r.names.push_back(name);
    r.values.push_back(v->get<double>());
    r.sigmas.push_back(s->get<double>());
    r.units.push_back(p.value("unit", std::string()));
  }
  *out = std::move(r);
  return Status();
}

}  // namespace kincal
