// A recording: commanded controls and measured target poses on one time base.
//
// Readers for the formats kincal accepts. Every reader returns bad input as an error Status
// naming the file, the line (or LCM event) and what was expected; nothing
// is silently dropped: repeated timestamps, reordered rows and skipped rows are counted in
// RecordingStats and reported by the caller, and a repeated timestamp whose values differ
// from the sample before it is a warning too.
//
// Time: files carry seconds on any epoch; on reading, times become int64 ns relative to
// the recording's origin (the earliest time in either stream), stored in `origin_s`.
#pragma once

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/model.h"
#include "kincal/status.h"
#include "kincal/text.h"

namespace kincal {

// A measured pose in a recording (CSV, MR.CLAM, LCM log).
struct RecordedPose {
  TimeNs t_ns = 0;                              // recording time base
  Eigen::Vector3d z = Eigen::Vector3d::Zero();  // x (m), y (m), theta (rad)
};

struct RecordingStats {
  int control_rows = 0;
  int pose_rows = 0;
  int control_repeated_times = 0;  // later row with the same time replaced the earlier
  int pose_repeated_times = 0;     // duplicate pose times: the later row kept
  int pose_rows_lost = 0;          // rows with no pose (empty or NaN: the tracker lost it), skipped
  int comment_lines = 0;
};

// One run of a recording: the robot may have been carried back to its start between runs,
// so nothing is predicted, fitted or carried across a run's start.
struct RecordingRun {
  TimeNs start_ns = 0;  // recording time base: the run's first sample
  std::string source;   // where it came from (a bag's path), may be empty
};

struct Recording {
  std::string source;      // human-readable origin ("file.csv + file.csv", "MR.CLAM robot 3")
  double origin_s = 0.0;   // file time of t_ns = 0
  ControlSignal controls;  // commanded controls, model's channel order
  std::vector<RecordedPose> poses;  // sorted by time, unique times
  RecordingStats stats;
  std::vector<std::string> warnings;  // suspicious but readable input
  // Runs in time order (start_ns increasing), the first at or before every sample; empty:
  // the recording is one run.
  std::vector<RecordingRun> runs;
};

// How much of a recording is read. A recording is held in memory whole, so memory is
// bounded by this, not by the input: a file (a CSV, an MR.CLAM .dat) of more lines, or a
// log with more samples on either channel, is refused with an error naming it.
struct RecordingLimits {
  int max_rows = kMaxTextLines;  // 5 000 000: 14 h of poses at 100 Hz
  bool IsValid(std::string* why) const;
};
// What an error past max_rows adds, in parentheses: why, and how to raise it.
inline constexpr std::string_view kMaxRowsAdvice =
    "a recording is held in memory whole; kincal analyze --max-rows raises the bound";

// The index of the run holding time t_ns (0 when the recording is one run).
int RunOf(const Recording& rec, TimeNs t_ns);

// Several recordings of one robot (files given one after another) as one recording of
// runs, in the order given: each part's runs (one if it has none) follow the previous
// part's. A part keeps its own times when it starts at least kRunGapS after the previous
// one ends; otherwise it is moved to start kRunGapS after it (each file on its own
// epoch, or files out of order), and a warning says so. Runs are never joined: nothing
// predicts across a run's start. The parts must have the same control channels.
inline constexpr double kRunGapS = 1.0;
StatusOr<Recording> JoinRuns(std::vector<Recording> parts);

// Controls recorded as positions (wheel encoders: cumulative counts, or angles in rad) to
// the rates the models take: over each interval between samples, the position difference
// over its duration (exact for the increment), held from the interval's start; the last
// sample of a run holds its last rate. Counts become radians by 2 pi / counts_per_rev
// (counts_per_rev 0: the positions are radians, and a joint reported in (-pi, pi] is
// unwrapped). Counts of a 16- or 32-bit register that rolls over are unwrapped, and a
// warning says which channels and how often. Never across a run's start. An error names
// the recording when a run has fewer than two samples.
Status PositionsToRates(double counts_per_rev, Recording* rec);

// C.csv: header "t,<control names of the model>" (any column order, extra columns are an
// error); P.csv: header "t,x,y,theta", where a row whose pose is all empty or NaN (a tracker
// that lost the robot) is skipped, counted (pose_rows_lost) and said in a warning. Times in
// seconds, any epoch. An optional integer `run` column in both files numbers the runs.
// `positions`: the controls are wheel positions (encoder counts or angles,
// PositionsToRates), not checked against the plausible range of the model's rates.
StatusOr<Recording> ReadCsvRecording(const std::string& controls_csv, const std::string& poses_csv,
                                     const KinematicModel& model, bool positions = false,
                                     const RecordingLimits& limits = {});

// UTIAS MR.CLAM: DIR/RobotN_Odometry.dat (t v omega) and DIR/RobotN_Groundtruth.dat
// (t x y theta); '#' starts a comment. Controls are the unicycle model's (v, omega).
StatusOr<Recording> ReadMrclam(const std::string& dir, int robot,
                               const RecordingLimits& limits = {});

// A kincald recording (LCM event log): kincal.controls_t on `controls_channel` and
// kincal.pose_t on `pose_channel` (times from their utime fields); kincal.run_t on
// KINCAL_RUN (written by `kincal import` of several bags) marks where each run starts.
StatusOr<Recording> ReadLcmLog(const std::string& path, const KinematicModel& model,
                               const RecordingLimits& limits = {},
                               const std::string& controls_channel = "KINCAL_CONTROLS",
                               const std::string& pose_channel = "KINCAL_POSE");

}  // namespace kincal
