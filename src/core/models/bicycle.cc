// Bicycle: a car commanded as cars are (ackermann_msgs/AckermannDrive, VESC, F1TENTH): a
// forward speed v [m/s] and a front steering angle steer [rad]. Reference point: the
// rear-axle midpoint (lever_arm moves it to the tracked body). The realised speed and
// steering angle are the commanded ones through a gain, the angle also through an offset:
//   v_r   = k_v v
//   phi   = k_steer steer + steer_offset     (positive turns left)
//   omega = v_r tan(phi) / wheelbase
// For small angles only k_steer / wheelbase is seen; `--fix wheelbase=...` (the drawing's
// value) separates them.
#include <cmath>

#include "kincal/model.h"

namespace kincal {
namespace {

class Bicycle final : public ModelImpl<Bicycle> {
 public:
  std::string_view name() const override { return "bicycle"; }
  std::string_view description() const override {
    return "car-like, rear-axle reference; controls are the commanded speed (m/s) and "
           "steering angle (rad), as in ackermann_msgs";
  }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"k_v", "1", 1.0, 0.2, "forward motion"},  // realised over commanded speed
        {"k_steer", "1", 1.0, 0.2,
         "driving at several steering angles"},  // realised over commanded angle
        {"steer_offset", "rad", 0.0, 0.05, "straight driving and turns to both sides"},
        {"wheelbase", "m", 0.33, 0.1, "driving with the wheels steered",
         1e-3},  // front axle to rear axle
    };
    return kParams;
  }
  const std::vector<ControlInfo>& controls() const override {
    static const std::vector<ControlInfo> kControls = {{"v", "m/s"}, {"steer", "rad"}};
    return kControls;
  }
  bool has_steering() const override { return true; }
  int steering_channel() const override { return 1; }
  template <typename T>
  Twist<T> Eval(const T* p, const T* u) const {
    using std::tan;
    const T v = p[0] * u[0];
    return {v, T(0.0), v * tan(p[1] * u[1] + p[2]) / p[3]};
  }
};

}  // namespace

KINCAL_MODEL_FACTORY(Bicycle)

}  // namespace kincal
