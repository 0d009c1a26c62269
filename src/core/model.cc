#include "kincal/model.h"

#include <stdexcept>

namespace kincal {

int KinematicModel::ParamIndex(std::string_view n) const {
  const auto& p = params();
  for (size_t i = 0; i < p.size(); ++i) {
    if (p[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

int KinematicModel::ControlIndex(std::string_view n) const {
  const auto& c = controls();
  for (size_t i = 0; i < c.size(); ++i) {
    if (c[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

std::shared_ptr<const KinematicModel> MakeModel(std::string_view name) {
  auto m = ModelRegistry::Instance().Create(name);
  if (!m) {
    throw std::invalid_argument("unknown model '" + std::string(name) +
                                "' (known: " + ModelRegistry::Instance().KnownList() + ")");
  }
  return m;
}

}  // namespace kincal
