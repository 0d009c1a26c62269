#include "kincal/online/calibration_store.h"

#include <algorithm>

namespace kincal {
namespace {

// Levels beyond this would keep one block in 2^40: never reached by a bounded run.
constexpr int kMaxLevel = 40;
// The smallest capacities that hold a few blocks of a slow robot's data.
constexpr int kMinPoses = 1000;
constexpr int kMinControls = 1000;

}  // namespace

bool CalibrationStoreOptions::IsValid(std::string* error) const {
  if (max_poses < kMinPoses || max_controls < kMinControls) {
    *error = "calibration.max_poses and calibration.max_controls must be >= " +
             std::to_string(kMinPoses);
    return false;
  }
  if (!(block_s >= 0.5 && block_s <= 600.0)) {
    *error = "calibration.block_s must be in [0.5, 600] s";
    return false;
  }
  return true;
}

CalibrationStore::CalibrationStore(CalibrationStoreOptions options, int num_controls)
    : opt_(options), num_controls_(num_controls), block_ns_(SecondsToNs(options.block_s)) {
  pose_t_.reserve(static_cast<size_t>(opt_.max_poses));
  pose_z_.reserve(static_cast<size_t>(opt_.max_poses));
  control_t_.reserve(static_cast<size_t>(opt_.max_controls));
  control_v_.reserve(static_cast<size_t>(opt_.max_controls));
}

size_t CalibrationStore::MemoryBytes(const CalibrationStoreOptions& o) {
  return static_cast<size_t>(o.max_poses) * (sizeof(TimeNs) + sizeof(Eigen::Vector3d)) +
         static_cast<size_t>(o.max_controls) * (sizeof(TimeNs) + sizeof(ControlSignal::Values));
}

size_t CalibrationStore::AllocatedBytes() const {
  return pose_t_.capacity() * sizeof(TimeNs) + pose_z_.capacity() * sizeof(Eigen::Vector3d) +
         control_t_.capacity() * sizeof(TimeNs) +
         control_v_.capacity() * sizeof(ControlSignal::Values);
}

int64_t CalibrationStore::Block(TimeNs t) const { return (t - origin_ns_) / block_ns_; }

bool CalibrationStore::Kept(int64_t block) const { return block % (int64_t{1} << level_) == 0; }

void CalibrationStore::NewBase() {
  if (started_) rebase_ = true;
}

double CalibrationStore::span_s() const {
  if (!started_) return 0.0;
  return NsToSeconds(std::max({last_pose_ns_, last_control_ns_, origin_ns_}) - origin_ns_);
}

// A sample's store time: after a new time base, offset to follow the stored data; the
// run's first sample fixes the block grid's origin.
TimeNs CalibrationStore::StoreTime(TimeNs t_ns) {
  if (rebase_) {
    offset_ns_ = std::max(last_pose_ns_, last_control_ns_) + kBaseGapNs - t_ns;
    rebase_ = false;
  }
  const TimeNs t = t_ns + offset_ns_;
  if (!started_) {
    started_ = true;
    origin_ns_ = t;
  }
  return t;
}

bool CalibrationStore::AddControl(TimeNs t_ns, std::span<const double> values) {
  const TimeNs t = StoreTime(t_ns);
  if (t < last_control_ns_) {
    return false;
  }
  last_control_ns_ = t;
  ControlSignal::Values v{};
  std::copy_n(values.begin(), std::min<size_t>(values.size(), v.size()), v.begin());
  const int64_t b = Block(t);
  // In a dropped block only the last control stays: it replaces the one before it there.
  if (!Kept(b) && !control_t_.empty() && Block(control_t_.back()) == b) {
    control_t_.back() = t;
    control_v_.back() = v;
    return true;
  }
  if (control_t_.size() >= static_cast<size_t>(opt_.max_controls)) Thin();
  if (control_t_.size() >= static_cast<size_t>(opt_.max_controls)) return true;  // cannot hold
  control_t_.push_back(t);
  control_v_.push_back(v);
  return true;
}

bool CalibrationStore::AddPose(TimeNs t_ns, const Eigen::Vector3d& xytheta) {
  const TimeNs t = StoreTime(t_ns);
  if (t <= last_pose_ns_) {
    return false;
  }
  last_pose_ns_ = t;
  if (pose_t_.size() >= static_cast<size_t>(opt_.max_poses)) Thin();
  if (!Kept(Block(t)) || pose_t_.size() >= static_cast<size_t>(opt_.max_poses)) {
    ++poses_thinned_;
    return true;
  }
  pose_t_.push_back(t);
  pose_z_.push_back(xytheta);
  return true;
}

// One level up: the blocks the new level drops go, over the whole run (in place: the
// vectors keep their capacity).
void CalibrationStore::Thin() {
  if (level_ >= kMaxLevel) return;
  ++level_;
  size_t k = 0;
  for (size_t i = 0; i < pose_t_.size(); ++i) {
    if (!Kept(Block(pose_t_[i]))) {
      ++poses_thinned_;
      continue;
    }
    pose_t_[k] = pose_t_[i];
    pose_z_[k] = pose_z_[i];
    ++k;
  }
  pose_t_.resize(k);
  pose_z_.resize(k);
  k = 0;
  for (size_t i = 0; i < control_t_.size(); ++i) {
    const int64_t b = Block(control_t_[i]);
    const bool last_of_block = i + 1 == control_t_.size() || Block(control_t_[i + 1]) != b;
    if (!Kept(b) && !last_of_block) continue;
    control_t_[k] = control_t_[i];
    control_v_[k] = control_v_[i];
    ++k;
  }
  control_t_.resize(k);
  control_v_.resize(k);
}

Recording CalibrationStore::Snapshot(TimeNs until_ns, const std::string& source) const {
  const TimeNs until = until_ns + offset_ns_;
  Recording rec;
  rec.source = source;
  rec.controls = ControlSignal(num_controls_, origin_ns_);
  const auto nc = static_cast<size_t>(num_controls_);
  for (size_t i = 0; i < control_t_.size() && control_t_[i] <= until; ++i) {
    rec.controls.Append(control_t_[i], std::span<const double>(control_v_[i].data(), nc));
  }
  rec.poses.reserve(pose_t_.size());
  for (size_t i = 0; i < pose_t_.size() && pose_t_[i] <= until; ++i) {
    rec.poses.push_back({pose_t_[i], pose_z_[i]});
  }
  rec.stats.control_rows = static_cast<int>(rec.controls.size());
  rec.stats.pose_rows = static_cast<int>(rec.poses.size());
  return rec;
}

}  // namespace kincal
