// The vocabulary of residual signatures: which component of a prediction error (along the
// track, across it, heading) correlates with which regressor (what the robot was told to
// do). An effect declares the terms its absence leaves in the residuals (Effect::
// signature()); `kincal analyze` (analysis/diagnosis.h) and the daemon's online model
// check (analysis/model_check.h) measure the same terms with these same names.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace kincal {

enum class ResidualComponent { kAlong, kCross, kHeading };
inline constexpr int kNumResidualComponents = 3;

// Regressors of a prediction window, from the commanded body twist (v: forward speed, w:
// turn rate) over the window. Listed in the order of their names (reports list them so).
enum class Regressor {
  kAbsSpeed,       // abs_speed       mean |v|
  kAbsTurnRate,    // abs_turn_rate   mean |w|
  kAccel,          // accel           v at the window's end minus v at its start
  kConst,          // const           1 (a bias)
  kCosHeading,     // cos_heading     cos of the heading at the window's start
  kLatAccel,       // lat_accel       mean v w
  kMoving,         // moving          fraction of the window with a command
  kSinHeading,     // sin_heading     sin of the heading at the window's start
  kSmallSpeed,     // small_speed     sign of v while |v| is under a quarter of its maximum
  kSmallTurn,      // small_turn      sign of w while |w| is under a quarter of its maximum
  kSpeed,          // speed           mean v
  kSteerReversal,  // steer_reversal  sign of the steering change over the last 0.5 s
  kTime,           // time            the window's start time
  kTurnRate,       // turn_rate       mean w
  kTurnRateSq,     // turn_rate_sq    mean w |w|
  kYawAccel,       // yaw_accel       w at the window's end minus w at its start
};
inline constexpr int kNumRegressors = 16;

struct SignatureTerm {
  ResidualComponent component;
  Regressor regressor;
};

std::string_view ComponentName(ResidualComponent c);
std::string_view RegressorName(Regressor r);
std::optional<Regressor> RegressorFromName(std::string_view name);

// One value per regressor, for the regressors that apply (steer_reversal needs a steering
// channel).
class RegressorValues {
 public:
  void Set(Regressor r, double value) {
    values_[static_cast<size_t>(r)] = value;
    present_ |= Bit(r);
  }
  bool Has(Regressor r) const { return (present_ & Bit(r)) != 0; }
  double operator[](Regressor r) const { return values_[static_cast<size_t>(r)]; }

 private:
  static constexpr uint32_t Bit(Regressor r) { return 1u << static_cast<int>(r); }
  std::array<double, kNumRegressors> values_{};
  uint32_t present_ = 0;
};

}  // namespace kincal
