// A file in this test process's scratch folder (made on first use), shared by the tests of
// every layer.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace kincal::testing {

inline std::string TempPath(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("kincal_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

}  // namespace kincal::testing
