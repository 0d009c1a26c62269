#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "commands.h"
#include "kincal/io/output_file.h"

namespace kincal::app {

Status CheckOutputFolder(const std::string& dir, const char* what) {
  namespace fs = std::filesystem;
  const std::string cannot = dir + ": cannot write the " + what + " here: ";
  std::error_code ec;
  fs::path p = fs::absolute(dir, ec);
  if (ec) return Status::Error(cannot + ec.message());
  // The folder itself when it exists, else the nearest folder above it that does.
  while (!fs::exists(p, ec) && p.has_parent_path() && p.parent_path() != p) p = p.parent_path();
  if (!fs::is_directory(p, ec)) {
    return Status::Error(cannot + p.string() + " is " +
                         (fs::exists(p, ec) ? "not a directory" : "missing"));
  }
  if (::access(p.c_str(), W_OK | X_OK) != 0) {
    return Status::Error(cannot + p.string() + ": " + std::strerror(errno));
  }
  return Status();
}

Status WriteOutput(const std::string& path, const std::string& text, const char* what) {
  return WriteFileAtomically(path, text, what);
}

}  // namespace kincal::app
