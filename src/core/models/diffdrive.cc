// Differential drive (thesis 3.3, heading row corrected).
//
//   v     = (R_R w_R + R_L w_L) / 2
//   omega = (R_R w_R - R_L w_L) / D
// Reference point: midpoint of the wheel axle. Positive wheel rates drive forward.
#include "kincal/model.h"

namespace kincal {
namespace {

class DiffDrive final : public ModelImpl<DiffDrive> {
 public:
  std::string_view name() const override { return "diffdrive"; }
  std::string_view description() const override {
    return "two driven wheels on one axle; controls are wheel rates";
  }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"r_l", "m", 0.03, 0.005, "forward motion and turns of several radii",
         1e-6},  // left wheel radius
        {"r_r", "m", 0.03, 0.005, "forward motion and turns of several radii",
         1e-6},  // right wheel radius
        {"d", "m", 0.15, 0.03, "turns of several radii, including turning in place",
         1e-6},  // wheel separation
    };
    return kParams;
  }
  const std::vector<ControlInfo>& controls() const override {
    static const std::vector<ControlInfo> kControls = {{"omega_l", "rad/s"}, {"omega_r", "rad/s"}};
    return kControls;
  }
  template <typename T>
  Twist<T> Eval(const T* p, const T* u) const {
    const T left = p[0] * u[0];
    const T right = p[1] * u[1];
    return {(right + left) * 0.5, T(0.0), (right - left) / p[2]};
  }
};

}  // namespace

KINCAL_MODEL_FACTORY(DiffDrive)

}  // namespace kincal
