// Simulation scenario files.
#include "kincal/sim/scenario.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <stdexcept>

#include "kincal/finite.h"
#include "kincal/yaml_file.h"

namespace kincal {

namespace {

// What reading a scenario throws on bad input; caught in LoadScenario, which returns it as a
// Status.
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The value of `key` in the map `n` (the section `section`, "" at the top), or `fallback`.
template <typename T>
T Get(const YAML::Node& n, const std::string& key, const T& fallback, const std::string& file,
      const std::string& section = "") {
  if (!n[key]) return fallback;
  const std::string where = file + ":" + std::to_string(n[key].Mark().line + 1) + ": key '" +
                            (section.empty() ? key : section + "." + key);
  T value;
  try {
    value = n[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw ScenarioError(where + "': " + e.msg);
  }
  if (!AllFinite(value)) throw ScenarioError(where + "': finite numbers expected");
  return value;
}

// Refuses a key of the map `n` that is not in `known` (a typo would be ignored silently),
// naming it with its section ("controls.lw"); `n` must be a map (or empty: the defaults).
void CheckKeys(const YAML::Node& n, const std::set<std::string>& known, const std::string& file,
               const std::string& section) {
  const std::string prefix = section.empty() ? "" : section + ".";
  if (n.IsNull()) return;
  if (!n.IsMap()) {
    throw ScenarioError(file + ":" + std::to_string(n.Mark().line + 1) + ": " +
                        (section.empty() ? "a scenario" : "'" + section + "'") +
                        " must be a map of keys");
  }
  for (const auto& kv : n) {
    const auto key = kv.first.as<std::string>();
    if (!known.count(key)) {
      throw ScenarioError(file + ":" + std::to_string(kv.first.Mark().line + 1) +
                          ": unknown key '" + prefix + key + "'");
    }
  }
}

Scenario LoadScenarioOrThrow(const std::string& file) {
  StatusOr<YAML::Node> loaded = LoadYamlFile(file, "scenario");
  if (!loaded.ok()) throw ScenarioError(loaded.status().message());
  const YAML::Node root = std::move(loaded).value();
  static const std::set<std::string> kKeys = {"model",          "truth",
                                              "hidden_effects", "estimator_effects",
                                              "guess",          "guess_sigma_fraction",
                                              "duration_s",     "seed",
                                              "controls",       "camera",
                                              "filter",         "control_psd",
                                              "report_every_s"};
  CheckKeys(root, kKeys, file, "");
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
    CheckKeys(c, {"profile", "low", "high", "min_period_s", "rate_hz"}, file, "controls");
    s.profile = Get(c, "profile", s.profile, file, "controls");
    s.control_low = Get(c, "low", s.control_low, file, "controls");
    s.control_high = Get(c, "high", s.control_high, file, "controls");
    s.min_period_s = Get(c, "min_period_s", s.min_period_s, file, "controls");
    s.control_rate_hz = Get(c, "rate_hz", s.control_rate_hz, file, "controls");
  }
  if (const auto c = root["camera"]) {
    CheckKeys(c, {"rate_hz", "jitter_max_s", "jitter_prob", "dropout_prob", "pose_sigma"}, file,
              "camera");
    s.camera.rate_hz = Get(c, "rate_hz", s.camera.rate_hz, file, "camera");
    s.camera.jitter_max_s = Get(c, "jitter_max_s", s.camera.jitter_max_s, file, "camera");
    s.camera.jitter_prob = Get(c, "jitter_prob", s.camera.jitter_prob, file, "camera");
    s.camera.dropout_prob = Get(c, "dropout_prob", s.camera.dropout_prob, file, "camera");
    const auto sigma = Get(c, "pose_sigma", std::vector<double>{}, file, "camera");
    if (!sigma.empty()) {
      if (sigma.size() != 3) throw ScenarioError(file + ": camera.pose_sigma needs 3 values");
      s.pose_sigma = Eigen::Vector3d(sigma[0], sigma[1], sigma[2]);
    }
  }
  std::string error;
  if (!s.IsValid(&error)) throw ScenarioError(file + ": " + error);
  return s;
}

}  // namespace

bool Scenario::IsValid(std::string* error) const {
  std::string camera_error;
  if (!camera.IsValid(&camera_error)) {
    *error = "camera: " + camera_error;
    return false;
  }
  const auto fail = [&](const char* why) {
    *error = why;
    return false;
  };
  if (!(duration_s > 0.0) || !(report_every_s > 0.0) || !(guess_sigma_fraction > 0.0))
    return fail("duration_s, report_every_s, guess_sigma_fraction must be > 0");
  if (!(duration_s <= kMaxScenarioDurationS))
    return fail("duration_s must be at most 2592000 s (30 days)");
  if (!(pose_sigma.array() > 0.0).all()) return fail("camera.pose_sigma must be > 0");
  if (!(min_period_s > 0.0) || !(control_rate_hz > 0.0) || !(control_rate_hz <= 10000.0))
    return fail("controls.min_period_s must be > 0 and controls.rate_hz in (0, 10000] Hz");
  if (control_low.size() != control_high.size())
    return fail("controls.low and controls.high need as many values");
  for (size_t i = 0; i < control_low.size(); ++i) {
    if (!(control_low[i] <= control_high[i]))
      return fail("controls.low must not exceed controls.high, channel by channel");
  }
  return true;
}

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
    const std::string problem = ParamValueProblem(sys.params()[static_cast<size_t>(i)], v);
    if (!problem.empty()) return Status::Error(what + ": " + problem);
    p[i] = v;
  }
  return p;
}

}  // namespace kincal
