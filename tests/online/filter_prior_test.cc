// Where the online estimator starts: a guess with its sigma fraction (of the value, or of
// the default sigma when the value is small), held parameters pinned with no correlation,
// and a checkpoint resumed by name (a parameter it held keeps this run's spread).
#include "kincal/online/filter_prior.h"

#include <gtest/gtest.h>

#include <cmath>

#include "kincal/plan/planner.h"

namespace kincal {
namespace {

TEST(FilterPrior, AGuessHasItsSigmaFractionAndHeldParametersArePinned) {
  const System sys = MakeSystem("diffdrive", {}).value();
  const int rl = sys.ParamIndex("r_l"), b = sys.ParamIndex("d");
  ASSERT_GE(rl, 0);
  ASSERT_GE(b, 0);
  const FilterPrior p = GuessedPrior(sys, {{"r_l", 0.05}}, 0.2, {{"d", 0.3}}, "test");
  EXPECT_DOUBLE_EQ(p.mean[rl], 0.05);
  const double default_sigma = sys.params()[static_cast<size_t>(rl)].default_sigma;
  EXPECT_DOUBLE_EQ(std::sqrt(p.covariance(rl, rl)), 0.2 * std::max(0.05, default_sigma));
  EXPECT_DOUBLE_EQ(p.mean[b], 0.3);
  EXPECT_DOUBLE_EQ(std::sqrt(p.covariance(b, b)),
                   kHeldSigmaFraction * sys.params()[static_cast<size_t>(b)].default_sigma);
  for (int k = 0; k < sys.num_params(); ++k) {
    if (k != b) {
      EXPECT_EQ(p.covariance(b, k), 0.0);
    }
  }
}

TEST(FilterPrior, ACheckpointIsResumedByNameAndAHeldOneKeepsThisRunsSpread) {
  const System sys = MakeSystem("diffdrive", {}).value();
  FilterPrior p = GuessedPrior(sys, {}, 0.2, {}, "test");
  const int rl = sys.ParamIndex("r_l"), rr = sys.ParamIndex("r_r"), b = sys.ParamIndex("d");
  const double b_var = p.covariance(b, b);
  Checkpoint ck;
  ck.names = {"r_l", "r_r", "d", "not_a_parameter"};
  ck.values = {0.051, 0.049, 0.31, 7.0};
  ck.covariance = Eigen::Matrix4d::Identity() * 1e-6;
  ck.covariance(0, 1) = ck.covariance(1, 0) = 5e-7;
  ck.covariance(2, 2) = 0;
  ck.held = {"d"};
  EXPECT_EQ(ResumeFrom(sys, ck, &p), 3);
  EXPECT_DOUBLE_EQ(p.mean[rl], 0.051);
  EXPECT_DOUBLE_EQ(p.mean[rr], 0.049);
  EXPECT_DOUBLE_EQ(p.covariance(rl, rr), 5e-7);
  EXPECT_DOUBLE_EQ(p.mean[b], 0.31);
  EXPECT_DOUBLE_EQ(p.covariance(b, b), b_var);  // held there: free here, this run's spread
}

}  // namespace
}  // namespace kincal
