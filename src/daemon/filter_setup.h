// The online estimator as kincald configures it: its options and its prior from the
// daemon's configuration (and the checkpoint resumed).
#pragma once

#include <optional>

#include "kincal/daemon/config.h"
#include "kincal/io/checkpoint.h"
#include "kincal/online/filter_stage.h"
#include "kincal/status.h"
#include "kincal/system.h"

namespace kincal::daemon {

// The filter, robot, checkpoint and calibration sections and the health rate.
FilterStageOptions FilterStageOptionsFrom(const DaemonConfig& c);
// checkpoint.resume (--resume), read and checked against the robot's model; nothing when
// none is named. An error names the file.
StatusOr<std::optional<Checkpoint>> ReadResumed(const DaemonConfig& c, const System& sys);
// robot.guess with robot.guess_sigma_fraction; then the checkpoint resumed (--resume) where
// it names the model's parameters; robot.fixed held over both (the drawing wins). Logs what
// was resumed.
FilterPrior DaemonPrior(const System& sys, const DaemonConfig& c,
                        const std::optional<Checkpoint>& resume);

}  // namespace kincal::daemon
