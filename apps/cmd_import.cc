// kincal import: a ROS 1 or ROS 2 bag to a kincal LCM log. The work is done by
// scripts/kincal_import.py (rosbags, from PyPI, keeps ROS out of the C++ core); this
// command finds the script and the Python that has rosbags, and runs it in its place.
#include <string>

#include "commands.h"
#include "python_scripts.h"

namespace kincal::app {

Command AddImport(CLI::App& app) {
  // Everything after `import` belongs to the script (`kincal import --help` is its help).
  app.prefix_command();
  app.set_help_flag();
  app.footer(
      "Runs scripts/kincal_import.py with the venv's Python; `kincal import --help` lists "
      "its options.");
  return [&app]() -> StatusOr<int> {
    return ExecPythonScript("kincal_import.py", "KINCAL_IMPORT_SCRIPT", app.remaining(),
                            "rosbags and lcm");
  };
}

}  // namespace kincal::app
