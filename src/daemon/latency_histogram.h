// Frame-to-publish latency: a fixed histogram of 10 us bins up to 200 ms (beyond: the last
// bin). No allocation after construction.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace kincal::daemon {

class LatencyHistogram {
 public:
  void Add(double ms) {
    const int bin = std::clamp(static_cast<int>(ms * kBinsPerMs), 0, kBins - 1);
    ++bins_[static_cast<size_t>(bin)];
    ++count_;
    max_ms_ = std::max(max_ms_, ms);
  }
  // The upper edge of the bin holding the p-quantile (0 when empty).
  double Percentile(double p) const {
    if (count_ == 0) return 0.0;
    const int64_t want = static_cast<int64_t>(std::ceil(p * static_cast<double>(count_)));
    int64_t seen = 0;
    for (int i = 0; i < kBins; ++i) {
      seen += bins_[static_cast<size_t>(i)];
      if (seen >= want) return (i + 1) * kBinMs;
    }
    return kBins * kBinMs;
  }
  double max_ms() const { return max_ms_; }
  int64_t count() const { return count_; }
  void Reset() { *this = LatencyHistogram(); }

 private:
  static constexpr double kBinsPerMs = 100.0;
  static constexpr double kBinMs = 0.01;
  static constexpr int kBins = 20000;
  std::array<int64_t, kBins> bins_{};
  int64_t count_ = 0;
  double max_ms_ = 0.0;
};

}  // namespace kincal::daemon
