// Evaluation: open-loop prediction errors over one horizon are at the noise floor for the
// true parameters and grow with a wrong one; the residual tests see the bias it leaves.
#include "analysis/evaluation.h"

#include <gtest/gtest.h>

#include "analysis/analysis_test_util.h"

namespace kincal::analysis {
namespace {

struct Judged {
  Evaluation e;
  ResidualTests tests;
};

Judged Judge(double k_v) {
  static const Recording rec = testing::UnicycleRecording(120.0, {}, {}, 5);
  AnalyzeOptions o;
  o.model = "unicycle";
  o.pose_sigma = Eigen::Vector2d(0.001, 0.003);
  std::vector<std::string> warnings;
  const Dataset d = Prepare(rec, o, &warnings).value();
  const System sys = MakeSystem("unicycle").value();
  Eigen::VectorXd p(2);
  p << k_v, 0.8;
  Judged j{Evaluate(sys, p, d), {}};
  j.tests = TestResiduals(j.e, d.horizon);
  return j;
}

TEST(Evaluation, TrueParametersPredictAtTheNoiseFloor) {
  const Judged j = Judge(0.9);
  EXPECT_GT(j.e.held.windows, 100);
  // From a start pose with 1 mm / 3 mrad of noise, 1 s at up to 0.72 m/s: a few mm.
  EXPECT_LT(j.e.held.pos_rms_m, 0.004);
  EXPECT_LT(j.e.held.heading_rms_rad, 0.006);
  for (int c = 0; c < 3; ++c) EXPECT_LT(std::abs(j.tests.bias_z[c]), 4.0) << c;
}

TEST(Evaluation, ASpeedGainTenPercentOffShowsAsAlongTrackBias) {
  const Judged good = Judge(0.9), bad = Judge(0.81);
  // 10 % of about 0.3 m travelled per horizon: some 3 cm.
  EXPECT_GT(bad.e.held.pos_rms_m, 5.0 * good.e.held.pos_rms_m);
  EXPECT_NEAR(bad.e.held.heading_rms_rad, good.e.held.heading_rms_rad,
              0.2 * good.e.held.heading_rms_rad);
  EXPECT_GT(std::abs(bad.tests.bias_z[0]), 6.0);  // along; the true model stays under 4
  const Eigen::Vector2d sigma(0.001, 0.003);
  EXPECT_GT(Combined(bad.e.held, sigma), Combined(good.e.held, sigma));
}

}  // namespace
}  // namespace kincal::analysis
