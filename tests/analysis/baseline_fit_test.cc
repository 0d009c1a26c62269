// The baseline fit: the staged multi-start reaches the truth from guesses five times off
// either way, says the optimum is unique, and its sigmas cover the error; a straight-only
// recording's turn gain is named as not identifiable.
#include "analysis/baseline_fit.h"

#include <gtest/gtest.h>

#include "analysis/analysis_test_util.h"

namespace kincal::analysis {
namespace {

TEST(BaselineFit, GuessesFiveTimesOffReachTheTruth) {
  const Recording rec = testing::UnicycleRecording(90.0, {}, {}, 11);
  AnalyzeOptions o;
  o.model = "unicycle";
  std::vector<std::string> warnings;
  const Dataset d = Prepare(rec, o, &warnings).value();
  const System sys = MakeSystem("unicycle").value();
  for (const double factor : {5.0, 0.2}) {
    const Eigen::VectorXd p0 =
        InitialParams(sys, {{"k_v", 0.9 * factor}, {"k_omega", 0.8 * factor}}).value();
    FitReport report;
    const Fit f = FitBaseline(sys, d, p0, o, &report).value();
    ASSERT_TRUE(f.ok) << factor;
    EXPECT_TRUE(report.unique) << report.uniqueness;
    const auto est = Estimates(sys, f, 0, 2);
    EXPECT_NEAR(est[0].value, 0.9, 3 * est[0].sigma) << "x" << factor;
    EXPECT_NEAR(est[1].value, 0.8, 3 * est[1].sigma) << "x" << factor;
    EXPECT_LT(est[0].sigma, 0.01);
    EXPECT_TRUE(Unobservable(sys, f).empty());
  }
}

TEST(BaselineFit, UnknownInitialNamesAreErrors) {
  const System sys = MakeSystem("unicycle").value();
  EXPECT_FALSE(InitialParams(sys, {{"wheelbase", 0.3}}).ok());
  const Eigen::VectorXd p = InitialParams(sys, {{"k_omega", 0.7}}).value();
  EXPECT_EQ(p[0], sys.params()[0].default_value);
  EXPECT_EQ(p[1], 0.7);
}

// A start or a held value below a parameter's physical bound (which the fits hold): --fix
// d=0 once ended in "'r_l' is not identifiable" three times over, after a flood of Ceres
// warnings.
TEST(BaselineFit, ValuesBelowAPhysicalBoundAreErrors) {
  const System sys = MakeSystem("diffdrive").value();
  EXPECT_EQ(InitialParams(sys, {{"r_l", -0.03}}).status().message(),
            "--init: 'r_l' must be >= 1e-06 m (its physical bound), not -0.03");
  Eigen::VectorXd p0 = InitialParams(sys, {}).value();
  EXPECT_EQ(FixParams(sys, {{"d", 0.0}}, &p0).status().message(),
            "--fix: 'd' must be >= 1e-06 m (its physical bound), not 0");
  EXPECT_TRUE(FixParams(sys, {{"d", 0.148}}, &p0).ok());
}

}  // namespace
}  // namespace kincal::analysis
