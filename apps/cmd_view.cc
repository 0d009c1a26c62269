// kincal view: what kincald sees, on a page in the browser. The work is done by
// scripts/kincal_view.py (aiohttp and plotly.js from PyPI); this command runs it in its
// place, as `kincal import` runs its script.
#include <string>

#include "commands.h"
#include "python_scripts.h"

namespace kincal::app {

Command AddView(CLI::App& app) {
  // Everything after `view` belongs to the script (`kincal view --help` is its help).
  app.prefix_command();
  app.set_help_flag();
  app.footer(
      "Runs scripts/kincal_view.py with the venv's Python; `kincal view --help` lists "
      "its options.");
  return [&app]() -> StatusOr<int> {
    return ExecPythonScript("kincal_view.py", "KINCAL_VIEW_SCRIPT", app.remaining(),
                            "aiohttp, plotly and lcm");
  };
}

}  // namespace kincal::app
