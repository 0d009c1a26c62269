// Subcommands of the `kincal` tool. Each registers its options on the CLI11 app and
// returns the function that runs it (exit code).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace kincal::app {

using Command = std::function<int()>;

Command AddReproduce(CLI::App& app);
Command AddSimulate(CLI::App& app);
Command AddAnalyze(CLI::App& app);
Command AddCamcal(CLI::App& app);
Command AddTarget(CLI::App& app);
Command AddRender(CLI::App& app);
Command AddDetect(CLI::App& app);
Command AddFloorcal(CLI::App& app);
Command AddExport(CLI::App& app);

}  // namespace kincal::app
