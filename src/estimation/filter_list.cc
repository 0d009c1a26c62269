// The filters, in one explicit list with their names; its order is the registry's order
// (kincal/registry.h). Adding a filter: its file in this folder, ending with
// KINCAL_FILTER_FACTORY(Class), and its two lines here.
#include <utility>

#include "kincal/estimation/filter.h"

namespace kincal {

std::unique_ptr<Filter> NewSrDd2Filter();
std::unique_ptr<Filter> NewEkfFilter();
std::unique_ptr<Filter> NewUkfFilter();

void RegisterBuiltins(Registry<Filter>* registry) {
  using Make = std::unique_ptr<Filter> (*)();
  for (const auto& [name, make] : {
           std::pair<const char*, Make>{"dd2", &NewSrDd2Filter},
           std::pair<const char*, Make>{"ekf", &NewEkfFilter},
           std::pair<const char*, Make>{"ukf", &NewUkfFilter},
       }) {
    registry->Register(name, make);
  }
}

}  // namespace kincal
