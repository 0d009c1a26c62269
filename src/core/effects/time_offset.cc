// time_offset: the motion at time t follows the command stamped t - delay_s (a transport
// delay, or an offset between the robot's and the camera's clocks).
#include "kincal/effect.h"

namespace kincal {
namespace {

class TimeOffset final : public EffectImpl<TimeOffset> {
 public:
  std::string_view name() const override { return "time_offset"; }
  std::string_view description() const override {
    return "command stream delayed by delay_s relative to the poses";
  }
  std::vector<SignatureTerm> signature() const override {
    return {{ResidualComponent::kAlong, Regressor::kAccel},
            {ResidualComponent::kHeading, Regressor::kYawAccel}};
  }
  EffectStage stage() const override { return EffectStage::kControlTiming; }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"delay_s", "s", 0.0, 0.1,
         "changes of command: starts, stops, speed and turn-rate changes"}};
    return kParams;
  }
  template <class T>
  T DelayT(const T* p) const {
    return p[0];
  }
};

}  // namespace

KINCAL_EFFECT_FACTORY(TimeOffset)

}  // namespace kincal
