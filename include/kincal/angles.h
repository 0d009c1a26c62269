// Angle helpers. Angles are radians, counter-clockwise from the +x axis.
#pragma once

#include <cmath>
#include <numbers>

namespace kincal {

// Wraps an angle to (-pi, pi].
inline double WrapAngle(double a) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  a = std::fmod(a + std::numbers::pi, kTwoPi);
  if (a <= 0.0) a += kTwoPi;
  return a - std::numbers::pi;
}

// Jet version: shifts the value by a multiple of 2*pi, derivatives unchanged.
template <typename J>
J WrapAngleJet(const J& a) {
  const double wrapped = WrapAngle(a.a);
  return a + (wrapped - a.a);
}

}  // namespace kincal
