// Calibration checkpoints: the estimate (values and full covariance of every parameter)
// at a moment, as JSON. kincald writes one periodically and on shutdown, atomically
// (write to FILE.tmp, fsync, rename), and `--resume FILE` starts from it. `kincal export`
// turns one into YAML a robot's configuration can include.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace kincal {
class params_t;  // generated from lcm/params_t.lcm
}

namespace kincal::daemon {

struct Checkpoint {
  std::string model;
  std::vector<std::string> effects;
  std::string filter;
  int64_t utime = 0;  // of the last update, us, host realtime clock
  int64_t update_count = 0;
  std::vector<std::string> names, units;
  std::vector<double> values;
  Eigen::MatrixXd covariance;  // names.size() square
};

// The estimate a kincal.params_t carries (model, filter, time, values and covariance by
// name); `effects` are not in the message. Reuses *c's storage.
void FillCheckpoint(const kincal::params_t& m, const std::vector<std::string>& effects,
                    Checkpoint* c);

// Throws std::runtime_error naming the path on I/O failure.
void WriteCheckpoint(const std::string& path, const Checkpoint& c);
// Throws std::runtime_error naming the path and what is wrong.
Checkpoint ReadCheckpoint(const std::string& path);
// YAML: model, effects, parameters {name: {value, sigma, unit}}, and the covariance.
void WriteExportYaml(std::ostream& out, const Checkpoint& c, const std::string& source);

}  // namespace kincal::daemon
