// Triangularize: the lower-triangular square root of A A^T that the square-root filters use.
#include <gtest/gtest.h>

#include <random>

#include "kincal/estimation/filter.h"

namespace kincal {
namespace {

TEST(Triangularize, FactorReproducesTheProductAndIsLowerTriangular) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  CompoundMat A(5, 13);
  for (int i = 0; i < A.rows(); ++i)
    for (int j = 0; j < A.cols(); ++j) A(i, j) = g(rng);
  StateMat L;
  Triangularize(A, &L);
  EXPECT_LT((L * L.transpose() - A * A.transpose()).norm(), 1e-12);
  for (int i = 0; i < 5; ++i) {
    EXPECT_GE(L(i, i), 0.0);
    for (int j = i + 1; j < 5; ++j) EXPECT_EQ(L(i, j), 0.0);
  }
}

}  // namespace
}  // namespace kincal
