// The batch tier's memory of a run: every pose the filter took and every control it used,
// bounded by configuration, not by the run's length.
//
// Thinning: time is cut into blocks of `block_s` seconds from the first sample. At level
// L the store keeps the blocks whose index is a multiple of 2^L (level 0: every block).
// When either stream reaches its capacity the level rises by one and half of the kept
// blocks go, over the whole run, and new data are admitted at the same density: the run
// stays evenly covered from its first second to its last, as `kincal analyze` spreads its
// capped windows evenly over a recording. A dropped block leaves a gap of at least
// `block_s` seconds between poses, which no prediction window crosses; of its controls
// only the last stays (the one in force when the next kept block begins).
//
// Time: the pipeline's nanoseconds. After a new time base (a clock jumped back) the data go
// on after the stored data, `kBaseGapNs` later, so the run stays one ordered recording.
// Not thread-safe: the filter thread owns it; the batch worker gets a Snapshot().
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/io/recording.h"
#include "kincal/time.h"

namespace kincal {

struct CalibrationStoreOptions {
  int max_poses = 108'000;     // 1 h at 30 Hz
  int max_controls = 432'000;  // 1 h at 120 Hz
  double block_s = 4.0;        // thinning unit (several prediction horizons)
  bool IsValid(std::string* error) const;
};

class CalibrationStore {
 public:
  // Reserves the capacities at once: adding never allocates.
  CalibrationStore(CalibrationStoreOptions options, int num_controls);

  // Samples in time order on the current time base; an earlier one is ignored (false).
  bool AddControl(TimeNs t_ns, std::span<const double> values);
  bool AddPose(TimeNs t_ns, const Eigen::Vector3d& xytheta);
  // A new time base: what follows is stored after what is there.
  void NewBase();

  // The stored data up to `until_ns` (current time base) as a recording for Analyze.
  Recording Snapshot(TimeNs until_ns, const std::string& source) const;

  size_t num_poses() const { return pose_t_.size(); }
  size_t num_controls() const { return control_t_.size(); }
  int level() const { return level_; }
  int64_t poses_thinned() const { return poses_thinned_; }
  // The run's span the store covers, s (0 when empty).
  double span_s() const;
  // The newest pose's time since the first sample (store time, ns; 0 before a pose). It
  // depends on the poses only, so a lossless replay schedules by it identically.
  TimeNs pose_span_ns() const { return has_pose() ? last_pose_ns_ - origin_ns_ : 0; }
  bool has_pose() const { return last_pose_ns_ != std::numeric_limits<TimeNs>::min(); }
  // Store time = pipeline time (current time base) + offset.
  TimeNs offset_ns() const { return offset_ns_; }
  // The store's memory at capacity (its data; a snapshot takes as much again while a
  // batch runs).
  static size_t MemoryBytes(const CalibrationStoreOptions& o);
  // The memory its vectors hold now (capacity, not size).
  size_t AllocatedBytes() const;

  // Between two time bases: longer than any pose gap a prediction window crosses.
  static constexpr TimeNs kBaseGapNs = 60'000'000'000;

 private:
  TimeNs StoreTime(TimeNs t_ns);
  int64_t Block(TimeNs t) const;
  bool Kept(int64_t block) const;
  void Thin();

  CalibrationStoreOptions opt_;
  int num_controls_;
  TimeNs block_ns_;
  TimeNs origin_ns_ = 0;  // the first sample's time (store time)
  bool started_ = false;
  TimeNs offset_ns_ = 0;  // store time = pipeline time + offset
  // The newest sample of each stream (store time; the lowest time before the first).
  TimeNs last_pose_ns_ = std::numeric_limits<TimeNs>::min();
  TimeNs last_control_ns_ = std::numeric_limits<TimeNs>::min();
  bool rebase_ = false;  // the next sample starts a new time base
  int level_ = 0;
  int64_t poses_thinned_ = 0;
  std::vector<TimeNs> pose_t_;
  std::vector<Eigen::Vector3d> pose_z_;
  std::vector<TimeNs> control_t_;
  std::vector<ControlSignal::Values> control_v_;
};

}  // namespace kincal
