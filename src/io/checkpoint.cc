// Checkpoint files (JSON) and the YAML export.
#include "kincal/io/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <kincal/params_t.hpp>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "kincal/io/output_file.h"
#include "kincal/system.h"
#include "kincal/text.h"

namespace kincal {

void FillCheckpoint(const kincal::params_t& m, const std::vector<std::string>& effects,
                    Checkpoint* c) {
  c->model = m.model;
  c->effects = effects;
  c->source = m.source == kincal::params_t::SOURCE_BATCH ? "batch" : "filter";
  c->filter = m.estimator;
  c->utime = m.utime;
  c->update_count = m.update_count;
  c->names = m.names;
  c->units = m.units;
  c->values = m.values;
  const int n = m.num_params;
  c->covariance.resize(n, n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < n; ++k) {
      c->covariance(i, k) = m.covariance[static_cast<size_t>(i)][static_cast<size_t>(k)];
    }
  }
}

bool FindParameter(const Checkpoint& c, const std::string& name, double* value, double* sigma) {
  for (size_t i = 0; i < c.names.size(); ++i) {
    if (c.names[i] != name) continue;
    const auto k = static_cast<Eigen::Index>(i);
    *value = c.values[i];
    *sigma = std::sqrt(std::max(0.0, c.covariance(k, k)));
    return true;
  }
  return false;
}

void MarkHeld(const std::vector<std::string>& names, Checkpoint* c) {
  c->held.clear();
  for (size_t i = 0; i < c->names.size(); ++i) {
    if (std::find(names.begin(), names.end(), c->names[i]) == names.end()) continue;
    c->held.push_back(c->names[i]);
    c->covariance.row(static_cast<Eigen::Index>(i)).setZero();
    c->covariance.col(static_cast<Eigen::Index>(i)).setZero();
  }
}

Status WriteCheckpoint(const std::string& path, const Checkpoint& c) {
  if (!std::all_of(c.values.begin(), c.values.end(), [](double v) { return std::isfinite(v); }) ||
      !c.covariance.allFinite()) {
    return Status::Error(path + ": checkpoint not written: the estimate is not finite");
  }
  nlohmann::json j;
  j["format"] = "kincal-checkpoint";
  j["version"] = 1;
  j["model"] = c.model;
  j["effects"] = c.effects;
  j["source"] = c.source;
  if (c.source == "batch") {
    j["batch_sequence"] = c.batch_sequence;
    j["batch_poses"] = c.batch_poses;
  }
  j["filter"] = c.filter;
  j["utime"] = c.utime;
  j["update_count"] = c.update_count;
  j["names"] = c.names;
  j["units"] = c.units;
  j["values"] = c.values;
  std::vector<std::vector<double>> cov(static_cast<size_t>(c.covariance.rows()));
  for (int i = 0; i < c.covariance.rows(); ++i) {
    for (int k = 0; k < c.covariance.cols(); ++k)
      cov[static_cast<size_t>(i)].push_back(c.covariance(i, k));
  }
  j["covariance"] = cov;
  if (!c.held.empty()) j["held"] = c.held;
  return WriteFileAtomically(path, j.dump(1), "checkpoint");
}

namespace {

// A parameter's plausible magnitude: its generic guess or the spread of that guess.
double Scale(const ParamInfo& p) { return std::max(std::abs(p.default_value), p.default_sigma); }

}  // namespace

namespace {

// One parameter's value and variance (a held one: zero variance and no correlation).
bool ParameterIsPlausible(const ParamInfo& p, const Checkpoint& c, int k, bool held,
                          std::string* error) {
  const double value = c.values[static_cast<size_t>(k)];
  const double limit = kCheckpointMaxScale * Scale(p);
  if (!std::isfinite(value) || std::abs(value) > limit || value < p.min_value) {
    *error = "value of '" + p.name + "' (" + ShortNumber(value) + " " + p.unit +
             ") is not plausible: expected a finite value within +-" + ShortNumber(limit) +
             (std::isfinite(p.min_value) ? " and >= " + ShortNumber(p.min_value) : "");
    return false;
  }
  const double var = c.covariance(k, k);
  if (held) {
    if (!c.covariance.row(k).isZero(0.0) || !c.covariance.col(k).isZero(0.0)) {
      *error = "'" + p.name + "' is held but has a variance or a correlation: expected zeros";
      return false;
    }
    return true;
  }
  const double min_sigma = kCheckpointMinSigmaFraction * p.default_sigma;
  if (!(var >= min_sigma * min_sigma) || !(std::sqrt(var) <= limit)) {
    *error = "variance of '" + p.name + "' (" + ShortNumber(var) +
             ") is not plausible: expected a sigma between " + ShortNumber(min_sigma) + " and " +
             ShortNumber(limit) + " " + p.unit;
    return false;
  }
  return true;
}

// The covariance of the free parameters: symmetric positive definite.
bool FreeCovarianceIsValid(const Checkpoint& c, const std::vector<Eigen::Index>& free,
                           std::string* error) {
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd sub(m, m);
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) sub(a, b) = c.covariance(free[a], free[b]);
  }
  const double asym = m == 0 ? 0.0 : (sub - sub.transpose()).cwiseAbs().maxCoeff();
  if (m > 0 && !(asym <= 1e-9 * sub.diagonal().cwiseAbs().maxCoeff())) {
    *error = "covariance is not symmetric";
    return false;
  }
  if (m > 0 && Eigen::LLT<Eigen::MatrixXd>(sub).info() != Eigen::Success) {
    *error = "covariance is not positive definite";
    return false;
  }
  return true;
}

}  // namespace

bool CheckpointIsValid(const Checkpoint& c, std::string* error) {
  std::unique_ptr<System> sys;
  if (const Status s = MakeSystem(c.model, c.effects, {}, &sys); !s.ok()) {
    *error = "model and effects: " + s.message();
    return false;
  }
  const size_t n = static_cast<size_t>(sys->num_params());
  if (c.names.size() != n || c.values.size() != n || c.covariance.rows() != static_cast<int>(n) ||
      c.covariance.cols() != static_cast<int>(n)) {
    *error = "expected the " + std::to_string(n) + " parameters of model '" + c.model +
             "' with its effects, found " + std::to_string(c.names.size());
    return false;
  }
  for (const auto& h : c.held) {
    if (std::find(c.names.begin(), c.names.end(), h) == c.names.end()) {
      *error = "held parameter '" + h + "' is not a parameter of model '" + c.model + "'";
      return false;
    }
  }
  std::vector<Eigen::Index> free;
  for (size_t i = 0; i < n; ++i) {
    const ParamInfo& p = sys->params()[i];
    if (c.names[i] != p.name) {
      *error = "parameter " + std::to_string(i + 1) + " is '" + c.names[i] + "', expected '" +
               p.name + "'";
      return false;
    }
    const bool held = std::find(c.held.begin(), c.held.end(), p.name) != c.held.end();
    if (!ParameterIsPlausible(p, c, static_cast<int>(i), held, error)) return false;
    if (!held) free.push_back(static_cast<Eigen::Index>(i));
  }
  return FreeCovarianceIsValid(c, free, error);
}

namespace {

// Throws std::runtime_error naming the path and what is wrong; ReadCheckpoint turns that
// into its Status.
Checkpoint ParseCheckpoint(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open checkpoint: " + std::strerror(errno));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a JSON checkpoint: " + e.what());
  }
  Checkpoint c;
  try {
    if (j.at("format") != "kincal-checkpoint")
      throw std::runtime_error("format is not kincal-checkpoint");
    if (j.at("version") != 1)
      throw std::runtime_error("unsupported version " + j.at("version").dump());
    c.model = j.at("model").get<std::string>();
    c.effects = j.at("effects").get<std::vector<std::string>>();
    // Checkpoints before the batch tier have no source: the filter's.
    c.source = j.value("source", std::string("filter"));
    if (c.source != "filter" && c.source != "batch") {
      throw std::runtime_error("source is '" + c.source + "', expected filter or batch");
    }
    c.batch_sequence = j.value("batch_sequence", 0);
    c.batch_poses = j.value("batch_poses", 0);
    c.filter = j.at("filter").get<std::string>();
    c.utime = j.at("utime").get<int64_t>();
    c.update_count = j.at("update_count").get<int64_t>();
    c.names = j.at("names").get<std::vector<std::string>>();
    c.units = j.at("units").get<std::vector<std::string>>();
    c.values = j.at("values").get<std::vector<double>>();
    c.held = j.value("held", std::vector<std::string>{});
    const auto cov = j.at("covariance").get<std::vector<std::vector<double>>>();
    const size_t n = c.names.size();
    if (c.units.size() != n || c.values.size() != n || cov.size() != n) {
      throw std::runtime_error("names, units, values and covariance differ in length");
    }
    c.covariance.resize(static_cast<int>(n), static_cast<int>(n));
    for (size_t i = 0; i < n; ++i) {
      if (cov[i].size() != n)
        throw std::runtime_error("covariance row " + std::to_string(i) + " has the wrong length");
      for (size_t k = 0; k < n; ++k)
        c.covariance(static_cast<int>(i), static_cast<int>(k)) = cov[i][k];
      if (!std::isfinite(c.values[i]))
        throw std::runtime_error("value of '" + c.names[i] + "' is not finite");
    }
    if (!c.covariance.allFinite()) throw std::runtime_error("covariance is not finite");
    std::string invalid;
    if (!CheckpointIsValid(c, &invalid)) throw std::runtime_error(invalid);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return c;
}

}  // namespace

StatusOr<Checkpoint> ReadCheckpoint(const std::string& path) {
  try {
    return ParseCheckpoint(path);
  } catch (const std::exception& e) {
    return Status::Error(e.what());
  }
}

namespace {

// A YAML scalar: plain when it is a simple word, else double-quoted with escapes.
std::string YamlScalar(const std::string& s) {
  const bool plain = !s.empty() && std::all_of(s.begin(), s.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.' || ch == '-';
  });
  if (plain) return s;
  std::string q = "\"";
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      q += '\\';
      q += ch;
    } else if (ch == '\n') {
      q += "\\n";
    } else if (u < 0x20 || u == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", u);
      q += buf;
    } else {
      q += ch;
    }
  }
  return q + "\"";
}

// Text for a YAML comment: one line, control characters shown as '?'.
std::string CommentText(std::string s) {
  for (char& ch : s) {
    if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ch = '?';
  }
  return s;
}

}  // namespace

void WriteExportYaml(std::ostream& out, const Checkpoint& c, const std::string& source) {
  out << "# kincal calibration of a " << CommentText(c.model) << " robot, from "
      << CommentText(source) << "\n";
  if (c.source == "batch" && c.batch_sequence > 0) {
    out << "# the batch calibration (batch " << c.batch_sequence << ", " << c.batch_poses
        << " poses of the whole run, fitted as kincal analyze fits them); sigma is 1-sigma.\n";
  } else if (c.source == "batch") {  // from a log's last params_t, which names no batch
    out << "# the batch calibration (the whole run, fitted as kincal analyze fits it); sigma "
           "is 1-sigma.\n";
  } else {
    out << "# the filter's estimate (" << c.update_count << " pose updates, filter "
        << CommentText(c.filter) << "); sigma is 1-sigma.\n";
  }
  out << "source: " << YamlScalar(c.source) << "\n"
      << "model: " << YamlScalar(c.model) << "\n"
      << "effects: [";
  for (size_t i = 0; i < c.effects.size(); ++i) out << (i ? ", " : "") << YamlScalar(c.effects[i]);
  out << "]\nupdated_utime: " << c.utime << "\nparameters:\n" << std::setprecision(9);
  for (size_t i = 0; i < c.names.size(); ++i) {
    const double s =
        std::sqrt(std::max(0.0, c.covariance(static_cast<int>(i), static_cast<int>(i))));
    std::string unit = YamlScalar(c.units[i]);
    if (unit.front() != '"') unit = "\"" + unit + "\"";
    const bool held = std::find(c.held.begin(), c.held.end(), c.names[i]) != c.held.end();
    out << "  " << YamlScalar(c.names[i]) << ": {value: " << c.values[i]
        << ", sigma: " << std::setprecision(3) << s << std::setprecision(9) << ", unit: " << unit
        << (held ? ", held: true" : "") << "}\n";
  }
  out << "covariance:   # row-major, in the order of 'parameters'\n";
  for (int i = 0; i < c.covariance.rows(); ++i) {
    out << "  - [";
    for (int k = 0; k < c.covariance.cols(); ++k)
      out << (k ? ", " : "") << std::setprecision(6) << c.covariance(i, k);
    out << "]\n";
  }
}

}  // namespace kincal
