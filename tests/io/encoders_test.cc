// Encoder positions (cumulative counts or angles) to the rates the models take.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <tuple>

#include "kincal/io/recording.h"

namespace kincal {
namespace {

// Positions of two wheels turning at rates that change every sample, 0.05 s apart.
Recording Positions(const std::vector<std::array<double, 2>>& rates, double per_rad,
                    double start = 0.0) {
  Recording rec;
  rec.source = "encoders";
  rec.controls = ControlSignal(2, 0);
  std::array<double, 2> pos = {start, start};
  for (size_t k = 0; k <= rates.size(); ++k) {
    const std::array<double, 2> counts = {pos[0] * per_rad, pos[1] * per_rad};
    rec.controls.Append(SecondsToNs(0.05 * static_cast<double>(k)), counts);
    if (k < rates.size()) {
      pos[0] += rates[k][0] * 0.05;
      pos[1] += rates[k][1] * 0.05;
    }
  }
  return rec;
}

TEST(Encoders, CountsDifferencedGiveEachIntervalsRateExactly) {
  const std::vector<std::array<double, 2>> rates = {{10, 12}, {11, 9}, {-3, 4}, {0, 0}};
  Recording rec = Positions(rates, 4096 / (2 * std::numbers::pi));
  ASSERT_TRUE(PositionsToRates(4096, &rec).ok());
  ASSERT_EQ(rec.controls.size(), 5u);
  for (size_t k = 0; k < rates.size(); ++k) {
    for (int c = 0; c < 2; ++c) {
      EXPECT_NEAR(rec.controls.ValuesAt(static_cast<int>(k))[static_cast<size_t>(c)],
                  rates[k][static_cast<size_t>(c)], 1e-9)
          << k;
    }
  }
  EXPECT_NEAR(rec.controls.ValuesAt(4)[0], 0.0, 1e-12);  // the last holds the last rate
}

TEST(Encoders, WrappedAnglesAreUnwrapped) {
  Recording rec;
  rec.source = "angles";
  rec.controls = ControlSignal(1, 0);
  for (int k = 0; k < 20; ++k) {
    const std::array<double, 1> a = {std::remainder(0.9 * k, 2 * std::numbers::pi)};
    rec.controls.Append(SecondsToNs(0.1 * k), a);
  }
  ASSERT_TRUE(PositionsToRates(0, &rec).ok());
  for (int k = 0; k + 1 < 20; ++k) EXPECT_NEAR(rec.controls.ValuesAt(k)[0], 9.0, 1e-9) << k;
}

// Counts of two wheels turning at constant rates (rad/s), 0.05 s apart, rounded and kept in
// a register of `modulus` counts (signed: [-modulus/2, modulus/2)), starting at `offset`.
Recording RegisterCounts(int samples, std::array<double, 2> rate, double per_rad, double offset,
                         double modulus, bool is_signed) {
  Recording rec;
  rec.source = "encoders";
  rec.controls = ControlSignal(2, 0);
  const double half = is_signed ? modulus / 2 : 0.0;
  for (int k = 0; k < samples; ++k) {
    std::array<double, 2> counts{};
    for (int c = 0; c < 2; ++c) {
      const double v = std::round(offset + rate[static_cast<size_t>(c)] * 0.05 * k * per_rad);
      counts[static_cast<size_t>(c)] =
          std::fmod(std::fmod(v + half, modulus) + modulus, modulus) - half;
    }
    rec.controls.Append(SecondsToNs(0.05 * k), counts);
  }
  return rec;
}

// Issue 34's sweep: a differential drive whose encoders are 16-bit registers (Kobuki's,
// iRobot Create's) reports counts that roll over from 65535 to 0; differenced as they were,
// each roll-over was a rate of -65536 counts in one sample, and `kincal analyze` fitted the
// track 6 % wide with exit 0. A counter of 16 or 32 bits, signed or not, is unwrapped and
// said; a jump that is no roll-over is left as it is.
TEST(Encoders, CountersThatRollOverAreUnwrappedAndSaid) {
  const double per_rad = 2578 / (2 * std::numbers::pi);  // a Kobuki wheel
  for (const auto& [modulus, offset, is_signed, name] :
       {std::tuple{65536.0, 60000.0, false, "16-bit"}, std::tuple{65536.0, 30000.0, true, "16-bit"},
        std::tuple{4294967296.0, 4294967296.0 - 20000.0, false, "32-bit"}}) {
    Recording rec = RegisterCounts(400, {12.0, -9.0}, per_rad, offset, modulus, is_signed);
    ASSERT_TRUE(PositionsToRates(2578, &rec).ok());
    for (int k = 0; k + 1 < static_cast<int>(rec.controls.size()); ++k) {
      EXPECT_NEAR(rec.controls.ValuesAt(k)[0], 12.0, 0.2) << name << " sample " << k;
      EXPECT_NEAR(rec.controls.ValuesAt(k)[1], -9.0, 0.2) << name << " sample " << k;
    }
    ASSERT_EQ(rec.warnings.size(), 1u) << name;
    EXPECT_NE(rec.warnings[0].find(std::string("a ") + name + " counter"), std::string::npos)
        << rec.warnings[0];
  }
  // Counts that never leave a 16-bit range but jump by a third of it (a gap in the log):
  // no roll-over, left as they are and not said.
  Recording gap;
  gap.source = "encoders";
  gap.controls = ControlSignal(2, 0);
  gap.controls.Append(0, std::array<double, 2>{100.0, 100.0});
  gap.controls.Append(SecondsToNs(0.05), std::array<double, 2>{30000.0, 100.5});
  gap.controls.Append(SecondsToNs(0.1), std::array<double, 2>{30001.0, 101.0});
  ASSERT_TRUE(PositionsToRates(2578, &gap).ok());
  EXPECT_GT(gap.controls.ValuesAt(0)[0], 1000.0);
  EXPECT_TRUE(gap.warnings.empty());
}

// Never across a run's start: each run's first rate comes from its own samples, and a run
// of one sample is an error naming it.
TEST(Encoders, RunsAreDifferencedOnTheirOwn) {
  // The second run's encoders stand far from where the first left them.
  Recording a = Positions({{10, 10}, {10, 10}}, 1.0),
            b = Positions({{-2, 5}, {-2, 5}}, 1.0, 1000.0);
  Recording joined = JoinRuns({a, b}).value();
  ASSERT_TRUE(PositionsToRates(0, &joined).ok());
  ASSERT_EQ(joined.controls.size(), 6u);
  EXPECT_NEAR(joined.controls.ValuesAt(2)[0], 10.0, 1e-9);  // run 1's last holds its rate
  EXPECT_NEAR(joined.controls.ValuesAt(3)[0], -2.0, 1e-9);  // run 2 from its own samples
  Recording single = Positions({}, 1.0);
  single.runs = {{0, "only"}};
  EXPECT_FALSE(PositionsToRates(0, &single).ok());
}

}  // namespace
}  // namespace kincal
