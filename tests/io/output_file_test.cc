// WriteFileAtomically: the whole text or nothing; links planted at the output or its
// temporary are replaced, never followed; a failure names the file, the step and errno's
// text and leaves no temporary behind.
#include "kincal/io/output_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace kincal {
namespace {

namespace fs = std::filesystem;

class OutputFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("kincal_output_file_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string Read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  fs::path dir_;
};

TEST_F(OutputFile, WritesTheWholeTextAndLeavesNoTemporary) {
  const std::string out = Path("report.json");
  std::string text(1 << 20, 'x');    // 1 MB: more than one write() may take
  text.append("\r\nend\0tail", 10);  // CR, LF and a NUL go through as they are
  ASSERT_TRUE(WriteFileAtomically(out, text, "report").ok());
  EXPECT_EQ(Read(out), text);
  EXPECT_FALSE(fs::exists(out + ".tmp"));
  ASSERT_TRUE(WriteFileAtomically(out, "second", "report").ok());  // replaces the old one
  EXPECT_EQ(Read(out), "second");
}

TEST_F(OutputFile, ALinkAtTheOutputIsReplacedAndItsTargetUntouched) {
  const std::string target = Path("precious.txt"), out = Path("checkpoint.json");
  std::ofstream(target) << "keep me";
  fs::create_symlink(target, out);
  ASSERT_TRUE(WriteFileAtomically(out, "{}", "checkpoint").ok());
  EXPECT_FALSE(fs::is_symlink(out));
  EXPECT_EQ(Read(out), "{}");
  EXPECT_EQ(Read(target), "keep me");
}

TEST_F(OutputFile, ALinkAtTheTemporaryIsRemovedNotFollowed) {
  const std::string target = Path("precious.txt"), out = Path("export.yaml");
  std::ofstream(target) << "keep me";
  fs::create_symlink(target, out + ".tmp");
  ASSERT_TRUE(WriteFileAtomically(out, "a: 1\n", "export").ok());
  EXPECT_EQ(Read(out), "a: 1\n");
  EXPECT_EQ(Read(target), "keep me");
  EXPECT_FALSE(fs::exists(out + ".tmp"));
}

TEST_F(OutputFile, AMissingFolderNamesTheFileTheStepAndErrno) {
  const std::string out = Path("no/such/folder/report.json");
  const Status s = WriteFileAtomically(out, "{}", "report");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), out + ".tmp: cannot create the report: No such file or directory");
}

TEST_F(OutputFile, AFolderInTheWayKeepsItAndLeavesNoTemporary) {
  const std::string out = Path("calibration.yaml");
  fs::create_directories(fs::path(out) / "inside");  // rename() cannot replace a folder
  const Status s = WriteFileAtomically(out, "k: 1\n", "calibration");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(out + ": cannot replace the calibration: "), std::string::npos)
      << s.message();
  EXPECT_TRUE(fs::is_directory(fs::path(out) / "inside"));
  EXPECT_FALSE(fs::exists(out + ".tmp"));
}

}  // namespace
}  // namespace kincal
