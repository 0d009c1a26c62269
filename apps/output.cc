#include <stdexcept>

#include "commands.h"
#include "kincal/io/output_file.h"

namespace kincal::app {

void WriteOutput(const std::string& path, const std::string& text, const char* what) {
  if (const Status s = WriteFileAtomically(path, text, what); !s.ok()) {
    throw std::runtime_error(s.message());
  }
}

}  // namespace kincal::app
