#include "python_scripts.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

extern char** environ;

namespace kincal::app {
namespace {

namespace fs = std::filesystem;

std::string FromEnv(const char* name) {
  const char* v = name != nullptr ? std::getenv(name) : nullptr;
  return v != nullptr ? std::string(v) : std::string();
}

fs::path ExecutableDir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : self.parent_path();
}

}  // namespace

std::string PythonInterpreter() {
  if (std::string p = FromEnv("KINCAL_PYTHON"); !p.empty()) return p;
  const fs::path venv = fs::path(KINCAL_SOURCE_DIR) / ".venv" / "bin" / "python";
  return fs::exists(venv) ? venv.string() : std::string("python3");
}

std::string PythonScript(const std::string& name, const char* env) {
  if (std::string p = FromEnv(env); !p.empty()) return p;
  const fs::path installed = ExecutableDir() / ".." / "share" / "kincal" / "scripts" / name;
  if (fs::exists(installed)) return installed.lexically_normal().string();
  return (fs::path(KINCAL_SOURCE_DIR) / "scripts" / name).string();
}

void SetLcmTypesPath() {
  if (!FromEnv("KINCAL_LCM_TYPES").empty()) return;
  const fs::path types = fs::path(KINCAL_BINARY_DIR) / "lcmgen" / "python";
  if (fs::exists(types)) ::setenv("KINCAL_LCM_TYPES", types.c_str(), 1);
}

Status ExecPythonScript(const std::string& name, const char* env,
                        const std::vector<std::string>& args, const std::string& needs) {
  std::vector<std::string> all = {PythonInterpreter(), PythonScript(name, env)};
  all.insert(all.end(), args.begin(), args.end());
  SetLcmTypesPath();
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execvp(argv[0], argv.data());
  return Status::Error("cannot run " + all[0] + " " + all[1] + ": " + std::strerror(errno) +
                       " (set KINCAL_PYTHON to a Python with " + needs + ")");
}

std::string RunAndWait(const std::vector<std::string>& args) {
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (const int e = ::posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ); e != 0) {
    return "cannot run " + args[0] + ": " + std::strerror(e);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return "waiting for " + args[0] + ": " + std::strerror(errno);
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  return args[0] + " " + (args.size() > 1 ? args[1] : "") + " failed (exit status " +
         std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
}

}  // namespace kincal::app
