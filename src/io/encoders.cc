// Wheel encoder positions to rates (recording.h, PositionsToRates).
#include <cmath>
#include <numbers>

#include "kincal/io/recording.h"

namespace kincal {
namespace {

// The samples [first, last) of one run as rates appended to `out`.
void RunRates(const ControlSignal& in, int first, int last, double scale, bool unwrap,
              ControlSignal* out) {
  const int nc = in.num_channels();
  std::array<double, kMaxControls> rate{};
  for (int k = first; k + 1 < last; ++k) {
    const double dt = in.TimeAt(k + 1) - in.TimeAt(k);
    const auto &a = in.ValuesAt(k), &b = in.ValuesAt(k + 1);
    for (int c = 0; c < nc; ++c) {
      double d = b[static_cast<size_t>(c)] - a[static_cast<size_t>(c)];
      if (unwrap && std::abs(d) > std::numbers::pi) d = std::remainder(d, 2 * std::numbers::pi);
      rate[static_cast<size_t>(c)] = scale * d / dt;
    }
    out->Append(in.ToNs(in.TimeAt(k)),
                std::span<const double>(rate.data(), static_cast<size_t>(nc)));
  }
  out->Append(in.ToNs(in.TimeAt(last - 1)),
              std::span<const double>(rate.data(), static_cast<size_t>(nc)));
}

}  // namespace

Status PositionsToRates(double counts_per_rev, Recording* rec) {
  const ControlSignal& in = rec->controls;
  const double scale = counts_per_rev > 0 ? 2 * std::numbers::pi / counts_per_rev : 1.0;
  ControlSignal out(in.num_channels(), in.origin_ns());
  const int n = static_cast<int>(in.size());
  int first = 0;
  while (first < n) {
    const int run = RunOf(*rec, in.ToNs(in.TimeAt(first)));
    int last = first + 1;
    while (last < n && RunOf(*rec, in.ToNs(in.TimeAt(last))) == run) ++last;
    if (last - first < 2) {
      return Status::Error(rec->source + ": run " + std::to_string(run + 1) +
                           " has one control sample: positions need two to give a rate");
    }
    RunRates(in, first, last, scale, counts_per_rev <= 0, &out);
    first = last;
  }
  rec->controls = std::move(out);
  return Status();
}

}  // namespace kincal
