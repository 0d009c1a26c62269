// Ackermann steering as a bicycle (thesis 3.4, corrected for a driven rear wheel).
//
// Reference point: rear-axle midpoint. The rear wheel is driven, the front wheel steers
// by phi_s = phi + steer_offset (positive turns left).
//   v     = R_B omega
//   omega_body = R_B omega tan(phi_s) / L
// (The thesis's extra cos(phi_s) in the translation rows belongs to a front-driven model.)
#include <cmath>

#include "kincal/model.h"

namespace kincal {
namespace {

class Ackermann final : public ModelImpl<Ackermann> {
 public:
  std::string_view name() const override { return "ackermann"; }
  std::string_view description() const override {
    return "car-like, driven rear axle, steered front wheel; controls are drive rate and "
           "steering angle";
  }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"r_b", "m", 0.05, 0.01, "forward motion", 1e-6},  // rear (virtual) wheel radius
        {"l", "m", 0.3, 0.06, "driving with the wheels steered", 1e-6},  // wheelbase
        {"steer_offset", "rad", 0.0, 0.05,
         "straight driving and turns to both sides"},  // added to the commanded steering angle
    };
    return kParams;
  }
  const std::vector<ControlInfo>& controls() const override {
    static const std::vector<ControlInfo> kControls = {{"omega", "rad/s"}, {"phi", "rad"}};
    return kControls;
  }
  bool has_steering() const override { return true; }
  int steering_channel() const override { return 1; }
  template <typename T>
  Twist<T> Eval(const T* p, const T* u) const {
    using std::tan;
    const T v = p[0] * u[0];
    return {v, T(0.0), v * tan(u[1] + p[2]) / p[1]};
  }
};

}  // namespace

KINCAL_MODEL_FACTORY(Ackermann)

}  // namespace kincal
