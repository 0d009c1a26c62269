// Simulation scenario files.
#include "kincal/sim/scenario.h"

#include <yaml-cpp/yaml.h>

#include <set>
#include <stdexcept>

#include "kincal/text.h"

namespace kincal {

namespace {

// What reading a scenario throws on bad input; caught in LoadScenario, which returns it as a
// Status.
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <typename T>
T Get(const YAML::Node& n, const std::string& key, const T& fallback, const std::string& file) {
  if (!n[key]) return fallback;
  try {
    return n[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw ScenarioError(file + ":" + std::to_string(n[key].Mark().line + 1) + ": key '" + key +
                        "': " + e.msg);
  }
}

Scenario LoadScenarioOrThrow(const std::string& file) {
  const StatusOr<std::string> text = ReadTextFile(file, "scenario");
  if (!text.ok()) throw ScenarioError(text.status().message());
  YAML::Node root;
  try {
    root = YAML::Load(text.value());
  } catch (const YAML::Exception& e) {
    throw ScenarioError(file + ": " + e.what());
  }
  static const std::set<std::string> kKeys = {"model",          "truth",
                                              "hidden_effects", "estimator_effects",
                                              "guess",          "guess_sigma_fraction",
                                              "duration_s",     "seed",
                                              "controls",       "camera",
                                              "filter",         "control_psd",
                                              "report_every_s"};
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (!kKeys.count(key)) {
      throw ScenarioError(file + ":" + std::to_string(kv.first.Mark().line + 1) +
                          ": unknown key '" + key + "'");
    }
  }
  Scenario s;
  s.model = Get(root, "model", s.model, file);
  s.truth = Get(root, "truth", s.truth, file);
  s.hidden_effects = Get(root, "hidden_effects", s.hidden_effects, file);
  s.estimator_effects = Get(root, "estimator_effects", s.estimator_effects, file);
  s.guess = Get(root, "guess", s.guess, file);
  s.guess_sigma_fraction = Get(root, "guess_sigma_fraction", s.guess_sigma_fraction, file);
  s.duration_s = Get(root, "duration_s", s.duration_s, file);
  s.seed = Get(root, "seed", s.seed, file);
  s.filter = Get(root, "filter", s.filter, file);
  s.control_psd = Get(root, "control_psd", s.control_psd, file);
  s.report_every_s = Get(root, "report_every_s", s.report_every_s, file);
  if (const auto c = root["controls"]) {
    s.profile = Get(c, "profile", s.profile, file);
    s.control_low = Get(c, "low", s.control_low, file);
    s.control_high = Get(c, "high", s.control_high, file);
    s.min_period_s = Get(c, "min_period_s", s.min_period_s, file);
    s.control_rate_hz = Get(c, "rate_hz", s.control_rate_hz, file);
  }
  if (const auto c = root["camera"]) {
    s.camera.rate_hz = Get(c, "rate_hz", s.camera.rate_hz, file);
    s.camera.jitter_max_s = Get(c, "jitter_max_s", s.camera.jitter_max_s, file);
    s.camera.jitter_prob = Get(c, "jitter_prob", s.camera.jitter_prob, file);
    s.camera.dropout_prob = Get(c, "dropout_prob", s.camera.dropout_prob, file);
    const auto sigma = Get(c, "pose_sigma", std::vector<double>{}, file);
    if (!sigma.empty()) {
      if (sigma.size() != 3) throw ScenarioError(file + ": camera.pose_sigma needs 3 values");
      s.pose_sigma = Eigen::Vector3d(sigma[0], sigma[1], sigma[2]);
    }
  }
  std::string error;
  if (!s.camera.IsValid(&error)) throw ScenarioError(file + ": camera: " + error);
  if (!(s.duration_s > 0.0) || !(s.report_every_s > 0.0) || !(s.guess_sigma_fraction > 0.0)) {
    throw ScenarioError(file + ": duration_s, report_every_s, guess_sigma_fraction must be > 0");
  }
  if (!(s.pose_sigma.array() > 0.0).all()) {
    throw ScenarioError(file + ": camera.pose_sigma must be > 0");
  }
  return s;
}

}  // namespace

StatusOr<Scenario> LoadScenario(const std::string& file) {
  try {
    return LoadScenarioOrThrow(file);
  } catch (const ScenarioError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    return Status::Error(file + ": " + e.what());
  }
}

StatusOr<VecN<kMaxState>> ParamsFrom(const System& sys, const std::map<std::string, double>& values,
                                     const std::string& what) {
  VecN<kMaxState> p(sys.num_params());
  for (int i = 0; i < sys.num_params(); ++i)
    p[i] = sys.params()[static_cast<size_t>(i)].default_value;
  for (const auto& [name, v] : values) {
    const int i = sys.ParamIndex(name);
    if (i < 0) return Status::Error(what + ": unknown parameter '" + name + "'");
    p[i] = v;
  }
  return p;
}

}  // namespace kincal
