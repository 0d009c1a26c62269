#include "kincal/control_signal.h"

#include <algorithm>
#include <cassert>

namespace kincal {

ControlSignal::ControlSignal(int num_channels, TimeNs origin_ns)
    : num_channels_(num_channels), origin_ns_(origin_ns) {
  assert(num_channels >= 0 && num_channels <= kMaxControls);
}

bool ControlSignal::Append(TimeNs t_ns, std::span<const double> values) {
  assert(static_cast<int>(values.size()) >= num_channels_);
  const double t = ToSeconds(t_ns);
  Values v{};
  std::copy_n(values.begin(), num_channels_, v.begin());
  if (!times_s_.empty()) {
    if (t < times_s_.back()) return false;
    if (t == times_s_.back()) {
      values_.back() = v;
      return true;
    }
  }
  times_s_.push_back(t);
  values_.push_back(v);
  return true;
}

int ControlSignal::IndexAt(double t_s) const {
  const auto it = std::upper_bound(times_s_.begin(), times_s_.end(), t_s);
  return static_cast<int>(it - times_s_.begin()) - 1;
}

const ControlSignal::Values& ControlSignal::ValuesAt(int i) const {
  return i < 0 ? zeros_ : values_[static_cast<size_t>(i)];
}

void ControlSignal::DiscardBefore(double t_s) {
  const int keep_from = IndexAt(t_s);
  if (keep_from <= 0) return;
  times_s_.erase(times_s_.begin(), times_s_.begin() + keep_from);
  values_.erase(values_.begin(), values_.begin() + keep_from);
}

}  // namespace kincal
