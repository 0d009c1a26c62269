// Finding kincal's Python scripts and the Python that runs them, for commands that hand
// work to a script (import, plan's plot).
#pragma once

#include <string>
#include <vector>

#include "kincal/status.h"

namespace kincal::app {

// $KINCAL_PYTHON, else the source tree's venv (scripts/setup makes it), else python3.
std::string PythonInterpreter();
// `env` if set, else the installed copy beside the other scripts (PREFIX/bin/kincal ->
// PREFIX/share/kincal/scripts/NAME), else the source tree's (a build tree's kincal).
std::string PythonScript(const std::string& name, const char* env);
// Points KINCAL_LCM_TYPES at the build tree's generated Python types when unset.
void SetLcmTypesPath();
// Runs scripts/NAME (PythonScript(name, env)) with the venv's Python and `args` in this
// process's place (the LCM types' path set); returns only with an error naming the command
// and `needs` (what the Python must have).
Status ExecPythonScript(const std::string& name, const char* env,
                        const std::vector<std::string>& args, const std::string& needs);
// Runs `args` (args[0] found on PATH) and waits; an error names the program and its exit.
std::string RunAndWait(const std::vector<std::string>& args);

}  // namespace kincal::app
