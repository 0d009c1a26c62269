#include "kincal/model.h"

#include <cmath>
#include <stdexcept>

#include "kincal/text.h"

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

Status MakeModel(std::string_view name, std::shared_ptr<const KinematicModel>* out) {
  *out = ModelRegistry::Instance().Create(name);
  if (!*out) {
    return Status::Error("unknown model '" + std::string(name) +
                         "' (known: " + ModelRegistry::Instance().KnownList() + ")");
  }
  return {};
}

StatusOr<std::shared_ptr<const KinematicModel>> MakeModel(std::string_view name) {
  std::shared_ptr<const KinematicModel> m;
  if (Status s = MakeModel(name, &m); !s.ok()) return s;
  return m;
}

std::string ParamNames(const std::vector<ParamInfo>& params) {
  std::string out;
  for (const auto& p : params) out += (out.empty() ? "" : ", ") + p.name;
  return out;
}

std::string ParamValueProblem(const ParamInfo& p, double v) {
  if (!std::isfinite(v)) return "'" + p.name + "' must be a finite number, not " + ShortNumber(v);
  if (v < p.min_value) {
    return "'" + p.name + "' must be >= " + ShortNumber(p.min_value) + " " + p.unit +
           " (its physical bound), not " + ShortNumber(v);
  }
  return "";
}

}  // namespace kincal
