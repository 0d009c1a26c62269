// lever_arm: the tracked target is offset from the kinematic reference point by
// (dx, dy) metres in the robot frame and rotated by dtheta:
//   x_t = x + cos(theta) dx - sin(theta) dy
//   y_t = y + sin(theta) dx + cos(theta) dy
//   theta_t = theta + dtheta
#include <cmath>

#include "kincal/effect.h"

namespace kincal {
namespace {

class LeverArm final : public EffectImpl<LeverArm> {
 public:
  std::string_view name() const override { return "lever_arm"; }
  std::string_view description() const override {
    return "target offset (dx, dy, dtheta) from the kinematic reference point";
  }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kAlong, Regressor::kTurnRate},
            {ResidualComponent::kCross, Regressor::kTurnRate},
            {ResidualComponent::kHeading, Regressor::kConst}};
  }
  EffectStage stage() const override { return EffectStage::kMeasurement; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"dx", "m", 0.0, 0.05, "rotation: turning in place or tight turns"},
        {"dy", "m", 0.0, 0.05, "rotation: turning in place or tight turns"},
        {"dtheta", "rad", 0.0, 0.05, "straight driving (heading against the direction of travel)"}};
    return kParams;
  }
  template <class T>
  void MeasureT(const T* p, Pose2<T>* pose) const {
    using std::cos;
    using std::sin;
    const T c = cos(pose->theta);
    const T s = sin(pose->theta);
    pose->x += c * p[0] - s * p[1];
    pose->y += s * p[0] + c * p[1];
    pose->theta += p[2];
  }
};

}  // namespace

KINCAL_EFFECT_FACTORY(LeverArm)

}  // namespace kincal
