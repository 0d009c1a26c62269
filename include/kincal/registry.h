// Registry<Base>: named factories for the pluggable parts (models, effects, filters).
// Each kind has one explicit list (src/core/models/model_list.cc,
// src/core/effects/effect_list.cc, src/estimation/filter_list.cc) whose order is the
// registry's order, whatever the build system does: `kincal analyze` tries and reports
// candidate effects in it, and the online model check names the first effect whose
// signature fits. The registry fills itself from that list on first use.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kincal {

template <typename Base>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Base>()>;

  static Registry& Instance() {
    static Registry registry = [] {
      Registry r;
      RegisterBuiltins(&r);  // the kind's list, found by argument-dependent lookup
      return r;
    }();
    return registry;
  }
  bool Register(std::string name, Factory f) {
    factories_.emplace_back(std::move(name), std::move(f));
    return true;
  }
  // nullptr if unknown.
  std::unique_ptr<Base> Create(std::string_view name) const {
    for (const auto& [n, f] : factories_) {
      if (n == name) return f();
    }
    return nullptr;
  }
  bool Has(std::string_view name) const {
    for (const auto& entry : factories_) {
      if (entry.first == name) return true;
    }
    return false;
  }
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const auto& entry : factories_) names.push_back(entry.first);
    return names;
  }
  // "a, b, c": for error messages naming what is known.
  std::string KnownList() const {
    std::string known;
    for (const auto& entry : factories_) known += (known.empty() ? "" : ", ") + entry.first;
    return known;
  }

 private:
  std::vector<std::pair<std::string, Factory>> factories_;
};

}  // namespace kincal
