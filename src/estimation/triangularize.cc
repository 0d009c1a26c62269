#include <cassert>
#include <cmath>

#include "kincal/estimation/filter.h"

namespace kincal {

void Triangularize(const CompoundMat& A, StateMat* L) {
  const int n = static_cast<int>(A.rows());
  const int m = static_cast<int>(A.cols());
  assert(m >= n);
  // Householder QR of B = A^T (m x n): B = Q R, so A A^T = R^T R and L = R^T.
  MatN<2 * (kMaxState + kMaxNoise), kMaxState> B = A.transpose();
  for (int k = 0; k < n && k < m; ++k) {
    const int len = m - k;
    auto x = B.col(k).segment(k, len);
    const double norm = x.norm();
    if (norm == 0.0) continue;
    const double alpha = x[0] > 0.0 ? -norm : norm;
    VecN<2 * (kMaxState + kMaxNoise)> v = x;
    v[0] -= alpha;
    const double vnorm2 = v.squaredNorm();
    if (vnorm2 == 0.0) continue;
    // B[k:, k:] -= 2 v (v^T B[k:, k:]) / (v^T v)
    for (int j = k; j < n; ++j) {
      const double s = 2.0 * v.dot(B.col(j).segment(k, len)) / vnorm2;
      B.col(j).segment(k, len) -= s * v;
    }
  }
  L->setZero(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) (*L)(i, j) = B(j, i);
  }
  for (int j = 0; j < n; ++j) {
    if ((*L)(j, j) < 0.0) L->col(j) *= -1.0;
  }
}

}  // namespace kincal
