// Wheel encoder positions to rates (recording.h, PositionsToRates).
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "kincal/io/recording.h"

namespace kincal {
namespace {

// A counter register's width, found from the counts themselves.
struct Register {
  double modulus = 0.0;  // counts per roll-over; 0: not a register that rolls over
  int bits = 0;
  int rollovers = 0;
};

// The register a channel's counts sit in: whole numbers that all fit 16 or 32 bits (signed
// or not) and that somewhere jump by more than half of it in one sample, which no wheel
// does (at 2578 counts a turn, half of 16 bits is 12 turns in a sample); else none.
Register FindRegister(const ControlSignal& in, int c) {
  double lo = INFINITY, hi = -INFINITY, jump = 0.0;
  bool whole = true;
  for (int k = 0; k < static_cast<int>(in.size()); ++k) {
    const double v = in.ValuesAt(k)[static_cast<size_t>(c)];
    whole = whole && v == std::floor(v);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    if (k > 0) jump = std::max(jump, std::abs(v - in.ValuesAt(k - 1)[static_cast<size_t>(c)]));
  }
  if (!whole) return {};
  for (const int bits : {16, 32}) {
    const double m = std::ldexp(1.0, bits);
    const bool fits = (lo >= 0 && hi < m) || (lo >= -m / 2 && hi < m / 2);
    if (fits) return jump > m / 2 ? Register{m, bits, 0} : Register{};
  }
  return {};
}

// One sample's difference of counts, a roll-over of `reg` taken out: a jump near a whole
// register is the counter wrapping, not the wheel (a jump that is neither is left as it is).
double Difference(double d, Register* reg) {
  if (reg->modulus == 0.0 || std::abs(d) <= reg->modulus / 2) return d;
  const double wrapped = std::remainder(d, reg->modulus);
  if (std::abs(wrapped) >= reg->modulus / 4) return d;
  ++reg->rollovers;
  return wrapped;
}

// The samples [first, last) of one run as rates appended to `out`.
void RunRates(const ControlSignal& in, int first, int last, double scale, bool unwrap,
              std::array<Register, kMaxControls>* regs, ControlSignal* out) {
  const int nc = in.num_channels();
  std::array<double, kMaxControls> rate{};
  for (int k = first; k + 1 < last; ++k) {
    const double dt = in.TimeAt(k + 1) - in.TimeAt(k);
    const auto &a = in.ValuesAt(k), &b = in.ValuesAt(k + 1);
    for (int c = 0; c < nc; ++c) {
      const auto i = static_cast<size_t>(c);
      double d = Difference(b[i] - a[i], &(*regs)[i]);
      if (unwrap && std::abs(d) > std::numbers::pi) d = std::remainder(d, 2 * std::numbers::pi);
      rate[i] = scale * d / dt;
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
  std::array<Register, kMaxControls> regs{};
  if (counts_per_rev > 0) {
    for (int c = 0; c < in.num_channels(); ++c) regs[static_cast<size_t>(c)] = FindRegister(in, c);
  }
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
    RunRates(in, first, last, scale, counts_per_rev <= 0, &regs, &out);
    first = last;
  }
  std::string rolled;
  for (int c = 0; c < in.num_channels(); ++c) {
    const Register& r = regs[static_cast<size_t>(c)];
    if (r.rollovers == 0) continue;
    rolled += std::string(rolled.empty() ? "" : ", ") + "channel " + std::to_string(c + 1) + " a " +
              std::to_string(r.bits) + "-bit counter " + std::to_string(r.rollovers) +
              (r.rollovers == 1 ? " time" : " times");
  }
  if (!rolled.empty()) {
    rec->warnings.push_back(rec->source + ": encoder counts rolled over and were unwrapped (" +
                            rolled + ")");
  }
  rec->controls = std::move(out);
  return Status();
}

}  // namespace kincal
