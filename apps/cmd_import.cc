// kincal import: a ROS 1 or ROS 2 bag to a kincal LCM log. The work is done by
// scripts/kincal_import.py (rosbags, from PyPI, keeps ROS out of the C++ core); this
// command finds the script and the Python that has rosbags, and runs it in its place.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"

namespace kincal::app {
namespace {

namespace fs = std::filesystem;

std::string FromEnv(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::string(v) : std::string();
}

fs::path ExecutableDir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : self.parent_path();
}

// $KINCAL_PYTHON, else the source tree's venv (scripts/setup makes it), else python3.
std::string Interpreter() {
  if (std::string p = FromEnv("KINCAL_PYTHON"); !p.empty()) return p;
  const fs::path venv = fs::path(KINCAL_SOURCE_DIR) / ".venv" / "bin" / "python";
  return fs::exists(venv) ? venv.string() : std::string("python3");
}

// The installed copy beside the other scripts (PREFIX/bin/kincal ->
// PREFIX/share/kincal/scripts), else the source tree's (a build tree's kincal).
std::string Script() {
  if (std::string p = FromEnv("KINCAL_IMPORT_SCRIPT"); !p.empty()) return p;
  const fs::path installed =
      ExecutableDir() / ".." / "share" / "kincal" / "scripts" / "kincal_import.py";
  if (fs::exists(installed)) return installed.lexically_normal().string();
  return (fs::path(KINCAL_SOURCE_DIR) / "scripts" / "kincal_import.py").string();
}

}  // namespace

Command AddImport(CLI::App& app) {
  // Everything after `import` belongs to the script (`kincal import --help` is its help).
  app.prefix_command();
  app.set_help_flag();
  app.footer(
      "Runs scripts/kincal_import.py with the venv's Python; `kincal import --help` lists "
      "its options.");
  return [&app]() -> int {
    std::vector<std::string> args = {Interpreter(), Script()};
    for (const auto& a : app.remaining()) args.push_back(a);
    if (FromEnv("KINCAL_LCM_TYPES").empty()) {
      const fs::path types = fs::path(KINCAL_BINARY_DIR) / "lcmgen" / "python";
      if (fs::exists(types)) ::setenv("KINCAL_LCM_TYPES", types.c_str(), 1);
    }
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execvp(argv[0], argv.data());
    throw std::runtime_error("import: cannot run " + args[0] + " " + args[1] + ": " +
                             std::strerror(errno) +
                             " (set KINCAL_PYTHON to a Python with rosbags and lcm)");
  };
}

}  // namespace kincal::app
