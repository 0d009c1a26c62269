// Whether the numbers of a value read from a file (a number, a list, a name -> number map)
// are all finite: the configuration readers refuse YAML's .nan and .inf by key with it.
// A value that holds no number is "finite" (a name, a flag).
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace kincal {

inline bool AllFinite(double v) { return std::isfinite(v); }
inline bool AllFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}
inline bool AllFinite(const std::map<std::string, double>& m) {
  return std::all_of(m.begin(), m.end(), [](const auto& kv) { return std::isfinite(kv.second); });
}
template <typename T>
bool AllFinite(const T&) {
  return true;
}

}  // namespace kincal
