#include "kincal/online/filter_options.h"

#include "kincal/estimation/filter.h"

namespace kincal {
namespace {

bool Expect(bool ok, const std::string& what, std::string* error) {
  if (!ok) *error = what;
  return ok;
}

}  // namespace

bool FilterOptions::IsValid(std::string* error) const {
  if (!FilterRegistry::Instance().Has(type)) {
    *error = "filter.type: unknown filter '" + type +
             "' (known: " + FilterRegistry::Instance().KnownList() + ")";
    return false;
  }
  for (double v : control_psd) {
    if (!Expect(v >= 0, "filter.control_psd must be >= 0", error)) return false;
  }
  for (double v : pose_psd) {
    if (!Expect(v >= 0, "filter.pose_psd must be >= 0", error)) return false;
  }
  return Expect(max_pose_gap_s > 0 && params_rate_hz >= 0 && control_history_s > 0,
                "filter.max_pose_gap_s, control_history_s must be > 0, params_rate_hz >= 0",
                error) &&
         Expect(gate_nis >= 0 && divergence_gated >= 1,
                "filter.gate_nis >= 0, divergence_gated >= 1", error) &&
         Expect(batch_window_s > 0 && batch_window_s <= control_history_s,
                "filter.batch_window_s must be in (0, control_history_s]", error);
}

}  // namespace kincal
