// kincald's health message: the counters, whole, and a one-line account of what is wrong
// now (what changed since the last message, and standing conditions such as no frames).
#pragma once

#include <kincal/health_t.hpp>
#include <string>

#include "kincal/daemon/daemon.h"
#include "kincal/time.h"

namespace kincal::daemon {

// What the pipeline reports beside its counters (copied under the pipeline's status lock).
struct HealthStatus {
  std::string source_name;
  std::string source_error;      // the source's current failure ("" when none)
  std::string last_frame_error;  // the newest frame the pose stage could not use
  std::string last_reject;       // the newest control message rejected
  std::string recorder_error;
  bool source_done = false;
  TimeNs since_last_frame_ns = 0;
  bool expects_lcm_controls = false;  // controls come over LCM (a live robot)
  std::string controls_channel;
  double latency_p50_ms = 0, latency_p99_ms = 0;  // since the last message
  int filter_status = 0;                          // of the last params_t (STATUS_*)
  std::string model_check_evidence;               // of the last model_check_t
  double seconds_without_target = 0;              // frame time
  double no_target_warn_s = 5.0;                  // report beyond this
};

// The whole run in one line (the daemon logs it when it stops).
std::string SummaryLine(const DaemonCounters& c);

// How a run ended, for its exit code.
struct EndOfRun {
  std::string checkpoint_path;   // --checkpoint ("" when none was asked for)
  std::string checkpoint_error;  // the last checkpoint write's failure
  std::string source_error;      // the source's failure
  std::string last_reject;       // the newest control message rejected
  bool has_estimate = false;     // the filter started (or resumed), or a batch calibrated
  bool source_ended = false;     // a log or simulation ran out (not stopped by a signal)
  DaemonCounters counters;
};
// What went wrong with the run's result ("" when nothing): a checkpoint write that failed,
// or a log or simulation that ran to its end without an estimate where a checkpoint was
// asked for or control messages were rejected, with why (poses, controls accepted and
// rejected, the last rejection). A log of frames alone (its poses are the product) and a run
// stopped by a signal before the filter started (a service stopped before the robot moved)
// are no error.
std::string EndOfRunError(const EndOfRun& e);
// 1, with EndOfRunError logged, when it is not empty or the source failed; else 0. A run
// stopped before the filter started, with a checkpoint asked for, is said in a warning.
int EndOfRunCode(const EndOfRun& e);

class HealthReporter {
 public:
  // Silence on the camera longer than this is reported.
  static constexpr TimeNs kNoFramesNs = 2 * kNsPerSecond;

  // The message for the period since the previous call (`period_s` long).
  void Build(const DaemonCounters& now, const HealthStatus& status, double period_s, int64_t utime,
             kincal::health_t* h);
  // Logs a message's account when it changes, and every kRepeatNs while it stands (the
  // message is published at health_rate_hz regardless); "health: ok" once it clears. True
  // when it logged.
  bool Log(const std::string& message, TimeNs now_mono_ns);

  static constexpr TimeNs kRepeatNs = 10 * kNsPerSecond;

 private:
  DaemonCounters prev_;
  std::string logged_;  // the account last logged
  TimeNs logged_at_ns_ = 0;
};

}  // namespace kincal::daemon
