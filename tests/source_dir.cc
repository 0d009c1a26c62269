#include "source_dir.h"

namespace kincal::testing {

const std::string& SourceDir() {
  static const std::string dir = KINCAL_SOURCE_DIR;
  return dir;
}

}  // namespace kincal::testing
