// The effects, in one explicit list. Its order is the registry's order (kincal/registry.h):
// `kincal analyze` tries and reports candidate effects in it, and the online model check
// names the first effect whose signature fits (time_offset before actuator_lag).
// Adding an effect: its file in this folder, ending with KINCAL_EFFECT_FACTORY(Class), and
// its two lines here.
#include "kincal/effect.h"

namespace kincal {

std::unique_ptr<Effect> NewTimeOffsetEffect();
std::unique_ptr<Effect> NewActuatorLagEffect();
std::unique_ptr<Effect> NewLeverArmEffect();
std::unique_ptr<Effect> NewYawRateBiasEffect();
std::unique_ptr<Effect> NewLateralSlipEffect();
std::unique_ptr<Effect> NewAsymmetricGainEffect();
std::unique_ptr<Effect> NewDeadBandEffect();
std::unique_ptr<Effect> NewBacklashEffect();
std::unique_ptr<Effect> NewEffectiveTrackEffect();
std::unique_ptr<Effect> NewTurnSlowdownEffect();

void RegisterBuiltins(Registry<Effect>* registry) {
  for (auto* make : {
           &NewTimeOffsetEffect,
           &NewActuatorLagEffect,
           &NewLeverArmEffect,
           &NewYawRateBiasEffect,
           &NewLateralSlipEffect,
           &NewAsymmetricGainEffect,
           &NewDeadBandEffect,
           &NewBacklashEffect,
           &NewEffectiveTrackEffect,
           &NewTurnSlowdownEffect,
       }) {
    registry->Register(std::string(make()->name()), make);
  }
}

}  // namespace kincal
