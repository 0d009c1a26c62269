// kincald's online guidance: the running estimate, every guidance.every_s of data time,
// handed to a worker thread that answers what to drive next (kincal/plan/advice.h) and
// publishes it as kincal.guidance_t. The filter thread only offers estimates; it never
// waits (an estimate offered while the worker is busy is skipped and counted).
#pragma once

#include <condition_variable>
#include <functional>
#include <kincal/guidance_t.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "kincal/daemon/config.h"
#include "kincal/io/checkpoint.h"
#include "kincal/plan/advice.h"

namespace kincal::daemon {

// What the guidance plans with, from an estimate: its own system (effects added online
// included), its values, and plan options with guidance.limits, targets, pose_sigma and
// pose_rate_hz. An error when the estimate does not fit its system or the options.
struct GuidancePlanning {
  std::unique_ptr<System> sys;
  Eigen::VectorXd params;
  PlanOptions options;
};
Status GuidancePlanningFrom(const GuidanceOptions& g, const Checkpoint& estimate,
                            GuidancePlanning* out);

class Guidance {
 public:
  using Publish = std::function<void(int64_t utime, const kincal::guidance_t&)>;
  // `options` must be valid for the configured robot (DaemonConfig::IsValid). `background`:
  // the worker runs below the pipeline (live; background_thread.h).
  Guidance(const GuidanceOptions& options, Publish publish, bool background = false);
  ~Guidance();
  Guidance(const Guidance&) = delete;
  Guidance& operator=(const Guidance&) = delete;

  // Called with every published estimate: starts advice when every_s of data time has
  // passed since the last and the worker is idle.
  void Offer(const Checkpoint& estimate);
  // Waits for the advice under way (tests, shutdown).
  void Drain();
  int64_t advised() const;
  int64_t skipped_busy() const;
  // The last error (an estimate the planner could not use), empty when none.
  std::string last_error() const;

 private:
  void Loop();
  void Advise(const Checkpoint& estimate);

  const GuidanceOptions opt_;
  const Publish publish_;
  const bool background_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false, busy_ = false;
  std::optional<Checkpoint> pending_;
  int64_t last_utime_ = 0;
  bool offered_ = false;
  int64_t advised_ = 0, skipped_busy_ = 0;
  std::string last_error_;
  std::thread thread_;
};

}  // namespace kincal::daemon
