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

ModelRegistry& ModelRegistry::Instance() {
  static ModelRegistry registry;
  return registry;
}

bool ModelRegistry::Register(std::string name, Factory f) {
  factories_.emplace_back(std::move(name), std::move(f));
  return true;
}

std::unique_ptr<KinematicModel> ModelRegistry::Create(std::string_view name) const {
  for (const auto& [n, f] : factories_) {
    if (n == name) return f();
  }
  return nullptr;
}

std::vector<std::string> ModelRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& entry : factories_) names.push_back(entry.first);
  return names;
}

std::shared_ptr<const KinematicModel> MakeModel(std::string_view name) {
  auto m = ModelRegistry::Instance().Create(name);
  if (!m) {
    std::string known;
    for (const auto& n : ModelRegistry::Instance().Names()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown model '" + std::string(name) + "' (known: " + known + ")");
  }
  return m;
}

}  // namespace kincal
