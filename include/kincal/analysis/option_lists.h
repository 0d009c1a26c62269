// The list options `kincal analyze` and kincald take as text, parsed with errors that name
// the item and what was expected (never a silent partial list).
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/status.h"

namespace kincal {

// "name=value,name=value" (--init, --fix): finite numbers by parameter name, each name
// once. Errors name `option`.
Status ParseInitList(std::string_view text, std::map<std::string, double>* out,
                     std::string_view option = "--init");
// "3,6,9" (--heldout-runs): run numbers >= 1, each once.
Status ParseRunList(std::string_view text, std::vector<int>* out);
// "effect,effect[ch1,ch2],..." (--effects): specs separated by commas outside brackets,
// each a valid spec (ParseEffectSpec). Brackets must balance.
Status ParseEffectList(std::string_view text, std::vector<std::string>* out);

}  // namespace kincal
