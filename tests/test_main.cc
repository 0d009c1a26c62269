#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace {

// The daemon tests' scratch folder (daemon_test_util.h: TempPath) holds recordings of
// hundreds of MB: removed when the process's tests are done, so that runs do not fill /tmp.
class RemoveScratch : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(
        std::filesystem::temp_directory_path() / ("kincal_test_" + std::to_string(::getpid())),
        ignored);
  }
};

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new RemoveScratch);
  return RUN_ALL_TESTS();
}
