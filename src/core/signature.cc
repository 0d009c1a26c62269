#include "kincal/signature.h"

namespace kincal {
namespace {

constexpr std::array<std::string_view, kNumRegressors> kRegressorNames = {
    "abs_speed", "abs_turn_rate", "accel",        "const",      "cos_heading", "lat_accel",
    "moving",    "sin_heading",   "small_speed",  "small_turn", "speed",       "steer_reversal",
    "time",      "turn_rate",     "turn_rate_sq", "yaw_accel"};

}  // namespace

std::string_view ComponentName(ResidualComponent c) {
  switch (c) {
    case ResidualComponent::kAlong:
      return "along";
    case ResidualComponent::kCross:
      return "cross";
    case ResidualComponent::kHeading:
      return "heading";
  }
  return "?";
}

std::string_view RegressorName(Regressor r) { return kRegressorNames[static_cast<size_t>(r)]; }

std::optional<Regressor> RegressorFromName(std::string_view name) {
  for (int i = 0; i < kNumRegressors; ++i) {
    if (kRegressorNames[static_cast<size_t>(i)] == name) return static_cast<Regressor>(i);
  }
  return std::nullopt;
}

}  // namespace kincal
