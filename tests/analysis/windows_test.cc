#include "analysis/windows.h"

#include <gtest/gtest.h>

#include <random>

#include "kincal/analysis/analyze.h"

namespace kincal::analysis {
namespace {

// 100 s of poses at 10 Hz with white noise of 2 mm / 4 mrad on a slow circle, controls at
// 50 Hz over the same span.
Recording Circle(double pos_sigma, double heading_sigma, double gap_from_s = -1) {
  Recording rec;
  rec.source = "synthetic";
  rec.controls = ControlSignal(2, 0);
  for (int k = 0; k <= 5000; ++k) {
    const double u[2] = {0.2, 0.1};
    rec.controls.Append(SecondsToNs(0.02 * k), u);
  }
  std::mt19937_64 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 0; k < 1000; ++k) {
    const double t = 0.1 * k;
    if (gap_from_s >= 0 && t >= gap_from_s && t < gap_from_s + 5) continue;
    const double th = 0.1 * t;
    rec.poses.push_back({SecondsToNs(t),
                         {2 * std::sin(th) + pos_sigma * n(rng),
                          2 - 2 * std::cos(th) + pos_sigma * n(rng), th + heading_sigma * n(rng)}});
  }
  return rec;
}

AnalyzeOptions Options() {
  AnalyzeOptions o;
  o.model = "unicycle";
  return o;
}

TEST(Windows, CutsFitAndHeldOutWindowsOfOneHorizon) {
  const Recording rec = Circle(0.002, 0.004);
  std::vector<std::string> warnings;
  const Dataset d = Prepare(rec, Options(), &warnings).value();
  EXPECT_TRUE(warnings.empty());
  EXPECT_NEAR(d.t_split, 0.7 * 99.9, 0.1);
  // Fit windows: non-overlapping 1 s windows over the first 70 s.
  EXPECT_EQ(d.fit_windows.size(), 69u);
  for (const Window& w : d.fit_windows) {
    EXPECT_NEAR(d.t[static_cast<size_t>(w.end)] - d.t[static_cast<size_t>(w.start)], 1.0, 1e-9);
    EXPECT_LE(d.t[static_cast<size_t>(w.end)], d.t_split + 1e-9);
  }
  // Evaluation windows start at every pose with a horizon end; none straddles the split.
  for (const Window& w : d.eval) {
    const bool fit = d.t[static_cast<size_t>(w.end)] <= d.t_split;
    const bool held = d.t[static_cast<size_t>(w.start)] >= d.t_split;
    EXPECT_TRUE(fit || held);
  }
  EXPECT_GT(d.eval.size(), 950u);
  // Each fit window gives its start and 8 poses over its span.
  EXPECT_EQ(d.fit_meas.size(), 9 * d.fit_windows.size());
}

TEST(Windows, EstimatesThePoseNoiseFromSecondDifferences) {
  const Dataset d = [] {
    static const Recording rec = Circle(0.002, 0.004);
    std::vector<std::string> w;
    return Prepare(rec, Options(), &w).value();
  }();
  EXPECT_NEAR(d.sigma[0], 0.002, 0.0002);
  EXPECT_NEAR(d.sigma[1], 0.004, 0.0004);
}

TEST(Windows, NoWindowSpansAGap) {
  static const Recording rec = Circle(0.002, 0.004, 30.0);
  std::vector<std::string> warnings;
  const Dataset d = Prepare(rec, Options(), &warnings).value();
  for (const Window& w : d.eval) {
    const double t0 = d.t[static_cast<size_t>(w.start)], t1 = d.t[static_cast<size_t>(w.end)];
    EXPECT_LT(t1 - t0, 1.11) << "a window from " << t0 << " s spans the 5 s gap";
  }
}

// A robot carried for 0.9 s (no poses, then put down elsewhere): a window that starts just
// before and ends just after would predict across the carry. None may.
TEST(Windows, NoWindowSpansAShortGapInside) {
  Recording rec = Circle(0.002, 0.004);
  std::vector<RecordedPose> kept;
  for (const auto& p : rec.poses) {
    const double t = NsToSeconds(p.t_ns);
    if (t > 30.05 && t < 30.95) continue;
    kept.push_back(p);
  }
  rec.poses = kept;
  std::vector<std::string> warnings;
  const Dataset d = Prepare(rec, Options(), &warnings).value();
  for (const Window& w : d.eval) {
    const double t0 = d.t[static_cast<size_t>(w.start)], t1 = d.t[static_cast<size_t>(w.end)];
    EXPECT_FALSE(t0 <= 30.05 && t1 >= 30.95) << "a window from " << t0 << " s spans the carry";
  }
  for (const Window& w : d.fit_windows) {
    const double t0 = d.t[static_cast<size_t>(w.start)], t1 = d.t[static_cast<size_t>(w.end)];
    EXPECT_FALSE(t0 <= 30.05 && t1 >= 30.95) << "a fit window from " << t0 << " s spans it";
  }
  EXPECT_GT(d.fit_windows.size(), 60u);
}

TEST(Windows, ATooShortRecordingIsAnErrorNamingIt) {
  Recording rec = Circle(0.002, 0.004);
  rec.poses.resize(15);
  std::vector<std::string> warnings;
  const StatusOr<Dataset> d = Prepare(rec, Options(), &warnings);
  ASSERT_FALSE(d.ok()) << "expected an error";
  EXPECT_NE(d.status().message().find("synthetic: only 15 poses"), std::string::npos)
      << d.status().message();
}

// Times written in milliseconds: the recording spans 100,000 "s" with poses 100 "s"
// apart, and the error blamed gaps or a short recording.
TEST(Windows, PosesFartherApartThanAHorizonAskWhetherTimeIsInSeconds) {
  const Recording ms = Circle(0.002, 0.004);
  Recording rec = ms;
  rec.controls = ControlSignal(2, 0);
  for (int k = 0; k < static_cast<int>(ms.controls.size()); ++k) {
    const auto& u = ms.controls.ValuesAt(k);
    rec.controls.Append(SecondsToNs(1000 * ms.controls.TimeAt(k)), std::span(u.data(), 2));
  }
  for (auto& p : rec.poses) p.t_ns *= 1000;
  std::vector<std::string> warnings;
  const StatusOr<Dataset> d = Prepare(rec, Options(), &warnings);
  ASSERT_FALSE(d.ok()) << "expected an error";
  EXPECT_NE(d.status().message().find("synthetic: the poses are 100 s apart (the median), more "
                                      "than the horizon of 1 s: is 't' in seconds?"),
            std::string::npos)
      << d.status().message();
}

}  // namespace
}  // namespace kincal::analysis
