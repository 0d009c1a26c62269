// ControlSignal: a time series of control samples held piecewise constant.
//
// Convention (zero-order hold forward): a sample applies from its own time until the
// next sample's time. Before the first sample the controls are zero (robot at rest).
// Samples with equal times: the later one wins. Times are int64 ns on the recording's
// time base; internally they are also kept as double seconds relative to `origin_ns()`
// so that propagation can work in seconds with full precision.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "kincal/time.h"
#include "kincal/types.h"

namespace kincal {

class ControlSignal {
 public:
  using Values = std::array<double, kMaxControls>;

  ControlSignal() = default;
  // `num_channels` <= kMaxControls; `origin_ns` fixes the double time base.
  ControlSignal(int num_channels, TimeNs origin_ns);

  int num_channels() const { return num_channels_; }
  TimeNs origin_ns() const { return origin_ns_; }
  size_t size() const { return times_s_.size(); }
  bool empty() const { return times_s_.empty(); }

  // Appends a sample. Returns false (and ignores it) when t is earlier than the last
  // sample: the caller decides how to report out-of-order input. A sample at the same
  // time replaces the previous one.
  bool Append(TimeNs t_ns, std::span<const double> values);

  // Seconds relative to origin.
  double ToSeconds(TimeNs t_ns) const { return NsToSeconds(t_ns - origin_ns_); }
  TimeNs ToNs(double t_s) const { return origin_ns_ + SecondsToNs(t_s); }

  // Index of the sample in force at time t (seconds rel. origin), -1 before the first.
  int IndexAt(double t_s) const;
  // Time (s rel. origin) of sample i.
  double TimeAt(int i) const { return times_s_[static_cast<size_t>(i)]; }
  // Values of sample i; i == -1 gives zeros.
  const Values& ValuesAt(int i) const;
  // Values in force at time t.
  const Values& At(double t_s) const { return ValuesAt(IndexAt(t_s)); }

  // Drops samples older than t (keeping the one in force at t). Bounds memory in
  // long-running use.
  void DiscardBefore(double t_s);

 private:
  int num_channels_ = 0;
  TimeNs origin_ns_ = 0;
  std::vector<double> times_s_;
  std::vector<Values> values_;
  Values zeros_{};
};

}  // namespace kincal
