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

#include "kincal/status.h"

namespace kincal {

class params_t;  // generated from lcm/params_t.lcm

struct Checkpoint {
  std::string model;
  std::vector<std::string> effects;
  // Whose estimate: "batch" (kincald's batch tier, kincal.calibration_t: the whole run
  // fitted as `kincal analyze` fits it) or "filter" (the real-time filter's, before the
  // first batch calibration).
  std::string source = "filter";
  int batch_sequence = 0;  // source "batch": the batch it comes from
  int batch_poses = 0;     // source "batch": the poses it was fitted to
  std::string filter;
  int64_t utime = 0;  // of the last update, us, host realtime clock
  int64_t update_count = 0;
  std::vector<std::string> names, units;
  std::vector<double> values;
  Eigen::MatrixXd covariance;  // names.size() square
  // Parameters held at their value (robot.fixed, kincal analyze --fix): not estimated, so
  // their rows and columns of the covariance are zero.
  std::vector<std::string> held;
};

// The estimate a kincal.params_t carries (model, filter, time, values and covariance by
// name; source from the message); `effects` are not in the message. Reuses *c's storage.
void FillCheckpoint(const kincal::params_t& m, const std::vector<std::string>& effects,
                    Checkpoint* c);

// A parameter's value and sigma by name; false when the estimate lacks it.
bool FindParameter(const Checkpoint& c, const std::string& name, double* value, double* sigma);

// Marks these parameters held (names not in the checkpoint are ignored): listed in
// c->held, their covariance rows and columns set to zero.
void MarkHeld(const std::vector<std::string>& names, Checkpoint* c);

// A checkpoint to resume from or export must describe a real estimate: a known model with
// its effects, every parameter of it in order, values finite, above the parameter's lower
// bound and within kCheckpointMaxScale of its plausible magnitude (the larger of its
// generic guess and that guess's sigma), each sigma at least kCheckpointMinSigmaFraction
// of the guess's sigma (a smaller one freezes the filter), and the covariance symmetric
// positive definite; a held parameter has zero variance and no correlation instead (the
// free ones' covariance is then positive definite). False with a message naming the
// parameter and what was expected.
inline constexpr double kCheckpointMaxScale = 1e3;
inline constexpr double kCheckpointMinSigmaFraction = 1e-5;
bool CheckpointIsValid(const Checkpoint& c, std::string* error);

// Writes atomically (path.tmp created exclusively, never through a link, fsynced, renamed
// over path). An error names the file, the step and errno's text, and leaves no temporary;
// a non-finite estimate is not written.
Status WriteCheckpoint(const std::string& path, const Checkpoint& c);

// An error names the path and what is wrong (CheckpointIsValid's message too).
StatusOr<Checkpoint> ReadCheckpoint(const std::string& path);
// YAML: model, effects, parameters {name: {value, sigma, unit}}, and the covariance.
void WriteExportYaml(std::ostream& out, const Checkpoint& c, const std::string& source);

}  // namespace kincal
