#include "kincal/analysis/option_lists.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "kincal/effect.h"

namespace kincal {
namespace {

// Calls `item` on each non-empty comma-separated item of `text`, in order, until one
// returns an error.
template <typename Fn>
Status ForEachItem(std::string_view text, Fn item) {
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view one = text.substr(start, comma - start);
    start = comma + 1;
    if (one.empty()) continue;
    if (Status s = item(one); !s.ok()) return s;
  }
  return {};
}

}  // namespace

Status ParseInitList(std::string_view text, std::map<std::string, double>* out,
                     std::string_view option) {
  const std::string opt(option);
  out->clear();
  return ForEachItem(text, [&](std::string_view item) -> Status {
    const size_t eq = item.find('=');
    if (eq == std::string_view::npos || eq == 0) {
      return Status::Error(opt + ": expected name=value, got '" + std::string(item) + "'");
    }
    const std::string_view value = item.substr(eq + 1);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    if (ec != std::errc() || end != value.data() + value.size() || !std::isfinite(v)) {
      return Status::Error(opt + ": '" + std::string(value) + "' is not a finite number (in '" +
                           std::string(item) + "')");
    }
    if (!out->emplace(std::string(item.substr(0, eq)), v).second) {
      return Status::Error(opt + ": '" + std::string(item.substr(0, eq)) + "' is given twice");
    }
    return {};
  });
}

Status ParseRunList(std::string_view text, std::vector<int>* out) {
  out->clear();
  return ForEachItem(text, [&](std::string_view item) -> Status {
    int v = 0;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (ec != std::errc() || end != item.data() + item.size() || v < 1) {
      return Status::Error("--heldout-runs: '" + std::string(item) +
                           "' is not a run number (1, 2, ...)");
    }
    if (std::find(out->begin(), out->end(), v) != out->end()) {
      return Status::Error("--heldout-runs: run " + std::string(item) + " is given twice");
    }
    out->push_back(v);
    return {};
  });
}

Status ParseEffectList(std::string_view text, std::vector<std::string>* out) {
  out->clear();
  std::string cur;
  int depth = 0;
  for (const char c : text) {
    if (c == '[') ++depth;
    if (c == ']' && --depth < 0) break;
    if (c == ',' && depth == 0) {
      if (!cur.empty()) out->push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (depth != 0) {
    out->clear();
    return Status::Error("--effects '" + std::string(text) +
                         "': unbalanced brackets (expected name or name[channel,...], separated "
                         "by commas)");
  }
  if (!cur.empty()) out->push_back(cur);
  for (const auto& spec : *out) {
    EffectSpec parsed;
    if (const Status s = ParseEffectSpec(spec, &parsed); !s.ok()) {
      out->clear();
      return Status::Error("--effects: " + s.message());
    }
  }
  return {};
}

}  // namespace kincal
