#include "commands.h"
#include "kincal/io/output_file.h"

namespace kincal::app {

Status WriteOutput(const std::string& path, const std::string& text, const char* what) {
  return WriteFileAtomically(path, text, what);
}

}  // namespace kincal::app
