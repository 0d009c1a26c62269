#include "daemon/filter_setup.h"

#include <spdlog/spdlog.h>

namespace kincal::daemon {

FilterStageOptions FilterStageOptionsFrom(const DaemonConfig& c) {
  FilterStageOptions o;
  o.filter = c.filter;
  o.effects = c.robot.effects;
  o.fixed = c.robot.fixed;
  o.model_check_every_s = 1.0 / c.health_rate_hz;
  o.checkpoint_path = c.checkpoint.path;
  o.checkpoint_every_s = c.checkpoint.every_s;
  o.auto_effects = c.robot.auto_effects;
  o.calibration.enabled = c.calibration.enabled;
  o.calibration.every_s = c.calibration.every_s;
  o.calibration.first_s = c.calibration.first_s;
  o.calibration.growth = c.calibration.growth;
  o.calibration.threads = c.calibration.threads;
  o.calibration.max_effects = c.calibration.max_effects;
  o.calibration.store.max_poses = c.calibration.max_poses;
  o.calibration.store.max_controls = c.calibration.max_controls;
  o.calibration.store.block_s = c.calibration.block_s;
  return o;
}

StatusOr<std::optional<Checkpoint>> ReadResumed(const DaemonConfig& c, const System& sys) {
  if (c.checkpoint.resume.empty()) return std::optional<Checkpoint>();
  StatusOr<Checkpoint> resume = ReadCheckpoint(c.checkpoint.resume);
  if (!resume.ok()) return resume.status();
  if (resume->model != sys.model().name()) {
    return Status::Error(c.checkpoint.resume + ": checkpoint is for model '" + resume->model +
                         "', the config says '" + std::string(sys.model().name()) + "'");
  }
  return std::optional<Checkpoint>(std::move(resume).value());
}

FilterPrior DaemonPrior(const System& sys, const DaemonConfig& c,
                        const std::optional<Checkpoint>& resume) {
  FilterPrior prior = GuessedPrior(sys, c.robot.guess, c.robot.guess_sigma_fraction, c.robot.fixed,
                                   c.file + ": robot.guess");
  if (resume) {
    const int matched = ResumeFrom(sys, *resume, &prior);
    HoldFixed(sys, c.robot.fixed, &prior.mean, &prior.covariance);  // the drawing wins
    spdlog::info("resumed {} of {} parameters from {} ({} updates)", matched, sys.num_params(),
                 c.checkpoint.resume, resume->update_count);
  }
  return prior;
}

}  // namespace kincal::daemon
