#include "options.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "kincal/text.h"

namespace kincal::app {
namespace {

// A check of the number `text` parses as (text that is no number is left to CLI11's own
// conversion, which names it).
CLI::Validator NumberCheck(std::function<bool(double)> ok, std::string expected) {
  return CLI::Validator(
      [ok = std::move(ok), expected = std::move(expected)](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || ok(v)) return {};
        return expected + " expected, not '" + text + "'";
      },
      "");
}

}  // namespace

CLI::Validator AtLeastZero() {
  return NumberCheck([](double v) { return v >= 0; }, "a number >= 0");
}

CLI::Validator AboveZero() {
  return NumberCheck([](double v) { return v > 0; }, "a number > 0");
}

CLI::Validator AtLeastOne() {
  return NumberCheck([](double v) { return v >= 1; }, "a number >= 1");
}

CLI::Validator AboveAndAtMost(double low, double high) {
  return NumberCheck([=](double v) { return v > low && v <= high; },
                     "a number in (" + ShortNumber(low) + ", " + ShortNumber(high) + "]");
}

CLI::Validator Between(double low, double high) {
  return NumberCheck([=](double v) { return v >= low && v <= high; },
                     "a number in [" + ShortNumber(low) + ", " + ShortNumber(high) + "]");
}

void RefuseNonFiniteNumbers(CLI::App& app) {
  const CLI::Validator finite =
      NumberCheck([](double v) { return std::isfinite(v); }, "a finite number");
  std::vector<CLI::App*> apps = app.get_subcommands([](CLI::App*) { return true; });
  apps.push_back(&app);
  for (CLI::App* a : apps) {
    for (CLI::Option* opt : a->get_options()) {
      if (opt->get_type_name() == "FLOAT") opt->check(finite);
    }
  }
}

}  // namespace kincal::app
