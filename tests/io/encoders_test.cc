// Encoder positions (cumulative counts or angles) to the rates the models take.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

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
