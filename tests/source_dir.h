// Where the source tree is, for tests that read its config/ and tests/data/. Defined in
// source_dir.cc alone, so that the path is in one translation unit's command line and the
// other test sources compile the same in every clone (ccache hits across clones).
#pragma once

#include <string>

namespace kincal::testing {

const std::string& SourceDir();

}  // namespace kincal::testing
