// The kinematic models, in one explicit list; its order is the registry's order
// (kincal/registry.h), in which `kincal models` lists them. Adding a model: its file in this
// folder, ending with KINCAL_MODEL_FACTORY(Class), and its two lines here.
#include "kincal/model.h"

namespace kincal {

std::unique_ptr<KinematicModel> NewDiffDriveModel();
std::unique_ptr<KinematicModel> NewUnicycleModel();
std::unique_ptr<KinematicModel> NewAckermannModel();
std::unique_ptr<KinematicModel> NewTricycleModel();
std::unique_ptr<KinematicModel> NewBicycleModel();

void RegisterBuiltins(Registry<KinematicModel>* registry) {
  for (auto* make : {
           &NewDiffDriveModel,
           &NewUnicycleModel,
           &NewAckermannModel,
           &NewTricycleModel,
           &NewBicycleModel,
       }) {
    registry->Register(std::string(make()->name()), make);
  }
}

}  // namespace kincal
