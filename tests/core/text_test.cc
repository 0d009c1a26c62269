// CleanLine, Escaped and ReadTextFile (src/core/text.cc): CRLF and a byte-order mark taken,
// invisible characters shown, a file read whole or an error with errno's text.
#include "kincal/text.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "temp_path.h"

namespace kincal {
namespace {

TEST(Text, CarriageReturnAndByteOrderMarkAreRemoved) {
  std::string line = "\xEF\xBB\xBFt,v,omega\r";
  CleanLine(&line, true);
  EXPECT_EQ(line, "t,v,omega");
  // A mark on a later line is not a mark: it stays (and a parser names it).
  line =
      "\xEF\xBB\xBF"
      "1,2\r";
  CleanLine(&line, false);
  EXPECT_EQ(line,
            "\xEF\xBB\xBF"
            "1,2");
  line = "1,2";  // nothing to remove
  CleanLine(&line, true);
  EXPECT_EQ(line, "1,2");
  line = "\r";
  CleanLine(&line, false);
  EXPECT_EQ(line, "");
}

TEST(Text, InvisibleCharactersAreShownEscaped) {
  EXPECT_EQ(Escaped("237.257\r"), "237.257\\r");
  EXPECT_EQ(Escaped("a\tb\nc\\d"), "a\\tb\\nc\\\\d");
  EXPECT_EQ(Escaped("\xEF\xBB\xBFx"), "\\xEF\\xBB\\xBFx");
  EXPECT_EQ(Escaped(std::string("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(Escaped("plain 1.5e-3"), "plain 1.5e-3");
}

TEST(Text, ReadTextFileReadsWholeOrSaysWhyNot) {
  const std::string path = testing::TempPath("text_test_read.yaml");
  const std::string text =
      std::string(kUtf8Bom) + "a: 1\r\nb: [2, 3]\r\n" + std::string(40000, '#');
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
  }
  const StatusOr<std::string> read = ReadTextFile(path, "layout");
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read.value(), text);  // byte for byte: the parser sees the mark and the CRs

  const StatusOr<std::string> small = ReadTextFile(path, "layout", 1000);
  ASSERT_FALSE(small.ok());
  EXPECT_EQ(small.status().message(), path + ": layout larger than 1000 bytes: not read");

  const std::string missing = testing::TempPath("text_test_missing.yaml");
  std::filesystem::remove(missing);
  const StatusOr<std::string> none = ReadTextFile(missing, "camera intrinsics");
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().message(),
            missing + ": cannot open camera intrinsics: No such file or directory");

  const std::string dir = std::filesystem::path(path).parent_path().string();
  const StatusOr<std::string> folder = ReadTextFile(dir, "config file");
  ASSERT_FALSE(folder.ok());
  EXPECT_EQ(folder.status().message(), dir + ": cannot open config file: Is a directory");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace kincal
