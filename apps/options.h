// Checks on the options of `kincal`'s commands and of `kincald` that say in words what
// was expected (CLI11's own range checks print the type's limits in full).
#pragma once

#include <CLI/CLI.hpp>

namespace kincal::app {

// A number >= 0 ("--noise: a number >= 0 expected, not '-1'").
CLI::Validator AtLeastZero();
// A number > 0.
CLI::Validator AboveZero();
// A number >= 1 (a count of runs, loops).
CLI::Validator AtLeastOne();
// A number in (low, high] ("--duration: a number in (0, 3600] expected, not '5000'").
CLI::Validator AboveAndAtMost(double low, double high);
// A number in [low, high].
CLI::Validator Between(double low, double high);
// Adds to every floating-point option of `app` and of each of its commands a check that
// refuses nan, inf and 1e999 by the option's name, before a command runs.
void RefuseNonFiniteNumbers(CLI::App& app);

}  // namespace kincal::app
