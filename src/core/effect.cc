#include "kincal/effect.h"

#include <algorithm>
#include <stdexcept>

namespace kincal {

std::string_view ToString(EffectStage s) {
  switch (s) {
    case EffectStage::kControlTiming:
      return "control timing";
    case EffectStage::kControlMap:
      return "control map";
    case EffectStage::kMotion:
      return "motion";
    case EffectStage::kMeasurement:
      return "measurement";
  }
  return "?";
}

bool BindChannels(const KinematicModel& model, const std::vector<std::string>& requested,
                  std::vector<int>* channels, std::string* error) {
  channels->clear();
  if (requested.empty()) {
    for (int c = 0; c < model.num_controls(); ++c) channels->push_back(c);
    return true;
  }
  for (const auto& ch : requested) {
    const int idx = model.ControlIndex(ch);
    if (idx < 0) {
      *error = "model '" + std::string(model.name()) + "' has no control '" + ch + "'";
      return false;
    }
    if (std::find(channels->begin(), channels->end(), idx) != channels->end()) {
      *error = "control '" + ch + "' listed twice";
      return false;
    }
    channels->push_back(idx);
  }
  return true;
}

Status MakeEffect(const EffectSpec& spec, const KinematicModel& model,
                  std::unique_ptr<Effect>* out) {
  auto e = EffectRegistry::Instance().Create(spec.name);
  if (!e) {
    return Status::Error("unknown effect '" + spec.name +
                         "' (known: " + EffectRegistry::Instance().KnownList() + ")");
  }
  if (!e->AppliesTo(model)) {
    return Status::Error("effect '" + spec.name + "' does not apply to model '" +
                         std::string(model.name()) + "'");
  }
  std::string error;
  if (!e->Bind(model, spec.channels, &error)) {
    return Status::Error("effect '" + spec.name + "': " + error);
  }
  *out = std::move(e);
  return {};
}

Status ParseEffectSpec(std::string_view text, EffectSpec* out) {
  EffectSpec spec;
  const auto open = text.find('[');
  if (open == std::string_view::npos) {
    spec.name = std::string(text);
    *out = std::move(spec);
    return {};
  }
  const auto close = text.find(']', open);
  if (close == std::string_view::npos || close != text.size() - 1) {
    return Status::Error("effect spec '" + std::string(text) +
                         "': expected name or name[channel,...]");
  }
  spec.name = std::string(text.substr(0, open));
  std::string_view list = text.substr(open + 1, close - open - 1);
  while (!list.empty()) {
    const auto comma = list.find(',');
    spec.channels.emplace_back(list.substr(0, comma));
    if (comma == std::string_view::npos) break;
    list.remove_prefix(comma + 1);
  }
  *out = std::move(spec);
  return {};
}

StatusOr<std::unique_ptr<Effect>> MakeEffect(const EffectSpec& spec, const KinematicModel& model) {
  std::unique_ptr<Effect> e;
  if (Status s = MakeEffect(spec, model, &e); !s.ok()) return s;
  return e;
}

StatusOr<EffectSpec> ParseEffectSpec(std::string_view text) {
  EffectSpec spec;
  if (Status s = ParseEffectSpec(text, &spec); !s.ok()) return s;
  return spec;
}

}  // namespace kincal
