// Tricycle: one front wheel steers and drives; two passive rear wheels. Read through
// encoders: steering angle phi = k_steer * steer + steer_offset, front wheel ground speed
// v_f = k_drive * drive. Reference point: rear-axle midpoint.
//   v     = v_f cos(phi)
//   omega = v_f sin(phi) / wheelbase
#include <cmath>

#include "kincal/model.h"

namespace kincal {
namespace {

class Tricycle final : public ModelImpl<Tricycle> {
 public:
  std::string_view name() const override { return "tricycle"; }
  std::string_view description() const override {
    return "front wheel steers and drives; controls are steering encoder ticks and drive "
           "encoder rate";
  }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"k_steer", "rad/tick", 0.001, 0.0002,
         "driving at several steering angles"},  // steering angle per encoder tick
        {"steer_offset", "rad", 0.0, 0.05,
         "straight driving and turns to both sides"},         // steering angle at zero ticks
        {"k_drive", "m/tick", 1e-4, 2e-5, "forward motion"},  // front-wheel travel per drive tick
        {"wheelbase", "m", 0.5, 0.1, "driving with the wheel steered",
         1e-6},  // front wheel to rear axle
    };
    return kParams;
  }
  const std::vector<ControlInfo>& controls() const override {
    static const std::vector<ControlInfo> kControls = {{"steer", "tick"}, {"drive", "tick/s"}};
    return kControls;
  }
  bool has_steering() const override { return true; }
  int steering_channel() const override { return 0; }
  template <typename T>
  Twist<T> Eval(const T* p, const T* u) const {
    using std::cos;
    using std::sin;
    const T phi = p[0] * u[0] + p[1];
    const T vf = p[2] * u[1];
    return {vf * cos(phi), T(0.0), vf * sin(phi) / p[3]};
  }
};

}  // namespace

KINCAL_MODEL_FACTORY(Tricycle)

}  // namespace kincal
