// Unicycle driven by velocity commands: the realised speed and turn rate are the
// commanded ones times constant scale factors.
//
//   v = k_v v_cmd,   omega = k_omega omega_cmd
#include "kincal/model.h"

namespace kincal {
namespace {

class Unicycle final : public ModelImpl<Unicycle> {
 public:
  std::string_view name() const override { return "unicycle"; }
  std::string_view description() const override {
    return "velocity-commanded robot; parameters are realised/commanded scales";
  }
  const std::vector<ParamInfo>& params() const override {
    static const std::vector<ParamInfo> kParams = {
        {"k_v", "1", 1.0, 0.2,
         "forward (or backward) motion"},       // realised / commanded forward speed
        {"k_omega", "1", 1.0, 0.2, "turning"},  // realised / commanded turn rate
    };
    return kParams;
  }
  const std::vector<ControlInfo>& controls() const override {
    static const std::vector<ControlInfo> kControls = {{"v", "m/s"}, {"omega", "rad/s"}};
    return kControls;
  }
  template <typename T>
  Twist<T> Eval(const T* p, const T* u) const {
    return {p[0] * u[0], T(0.0), p[1] * u[1]};
  }
};

}  // namespace

KINCAL_MODEL_FACTORY(Unicycle)

}  // namespace kincal
