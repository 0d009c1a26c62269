// Private helpers shared by the filter implementations.
#pragma once

#include <Eigen/Dense>
#include <cmath>

#include "kincal/angles.h"
#include "kincal/estimation/filter.h"

namespace kincal::internal {

// a - b, wrapping components i with (mask >> i) & 1.
template <typename Vec>
inline Vec WrappedDiff(const Vec& a, const Vec& b, uint32_t mask) {
  Vec d = a - b;
  for (int i = 0; i < static_cast<int>(d.size()); ++i) {
    if ((mask >> i) & 1u) d[i] = WrapAngle(d[i]);
  }
  return d;
}

inline uint32_t MeasAngleMask(const MeasurementFunction& h) {
  uint32_t m = 0;
  for (int i = 0; i < h.meas_dim(); ++i) {
    if (h.IsAngle(i)) m |= 1u << i;
  }
  return m;
}

inline uint32_t StateAngleMask(const ProcessFunction& f) {
  uint32_t m = 0;
  for (int i = 0; i < f.state_dim(); ++i) {
    if (f.IsAngle(i)) m |= 1u << i;
  }
  return m;
}

inline void WrapAngles(StateVec* x, uint32_t mask) {
  for (int i = 0; i < static_cast<int>(x->size()); ++i) {
    if ((mask >> i) & 1u) (*x)[i] = WrapAngle((*x)[i]);
  }
}

}  // namespace kincal::internal
