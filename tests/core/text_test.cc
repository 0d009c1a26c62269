// TextLines, Escaped and ReadTextFile (src/core/text.cc): every system's line endings, a
// byte-order mark and UTF-16 taken, invisible characters shown, a file read whole or an
// error with errno's text.
#include "kincal/text.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "temp_path.h"

namespace kincal {
namespace {

// The lines of a file written with `bytes`, or the error that ended them.
std::vector<std::string> LinesOf(const std::string& bytes, std::string* error = nullptr,
                                 size_t max_line_bytes = kMaxTextLineBytes,
                                 int max_lines = kMaxTextLines) {
  const std::string path = testing::TempPath("text_test_lines.txt");
  {
    std::ofstream out(path, std::ios::binary);
    out << bytes;
  }
  TextLines lines(path, "test file", max_line_bytes, max_lines);
  std::vector<std::string> out;
  std::string line;
  while (lines.Next(&line)) out.push_back(line);
  if (error) *error = lines.status().ok() ? "" : lines.status().message();
  EXPECT_EQ(lines.line_number(), static_cast<int>(out.size()));
  std::filesystem::remove(path);
  return out;
}

using Lines = std::vector<std::string>;

TEST(Text, LineEndingsOfEverySystemAndAByteOrderMark) {
  EXPECT_EQ(LinesOf("t,v\n1,2\n"), (Lines{"t,v", "1,2"}));
  EXPECT_EQ(LinesOf("t,v\r\n1,2\r\n"), (Lines{"t,v", "1,2"}));  // Windows
  EXPECT_EQ(LinesOf("\xEF\xBB\xBFt,v\r\n1,2"), (Lines{"t,v", "1,2"}));
  // Issue 34's sweep: a lone CR (classic Mac; Excel for Mac's "CSV (Macintosh)") made one
  // line of the whole file ("column '0' appears twice").
  EXPECT_EQ(LinesOf("t,v\r1,2\r3,4\r"), (Lines{"t,v", "1,2", "3,4"}));
  EXPECT_EQ(LinesOf("a\r\rb\n\nc"), (Lines{"a", "", "b", "", "c"}));
  EXPECT_EQ(LinesOf(""), (Lines{}));
  EXPECT_EQ(LinesOf("\xEF\xBB\xBF"), (Lines{}));
  // A mark on a later line is not a mark: it stays (and a parser names it).
  EXPECT_EQ(LinesOf("a\n\xEF\xBB\xBF"
                    "1"),
            (Lines{"a",
                   "\xEF\xBB\xBF"
                   "1"}));
  EXPECT_EQ(LinesOf("\xEF\xBB"), (Lines{"\xEF\xBB"}));  // half a mark is text
}

// Issue 34's sweep: a spreadsheet's "Unicode text" is UTF-16 with a byte-order mark, and read
// as bytes its header "lacked column 't'".
TEST(Text, Utf16IsReadAsUtf8) {
  const auto utf16 = [](const std::u16string& text, bool little) {
    std::string bytes = little ? "\xFF\xFE" : "\xFE\xFF";
    for (const char16_t u : text) {
      const char lo = static_cast<char>(u & 0xFF), hi = static_cast<char>(u >> 8);
      bytes += little ? std::string{lo, hi} : std::string{hi, lo};
    }
    return bytes;
  };
  EXPECT_EQ(LinesOf(utf16(u"t,x\r\n0,1.5\r\n", true)), (Lines{"t,x", "0,1.5"}));
  EXPECT_EQ(LinesOf(utf16(u"t,x\r0,1.5", false)), (Lines{"t,x", "0,1.5"}));
  // Beyond ASCII: θ (2 bytes of UTF-8), € (3), and 𝜃 (a surrogate pair, 4).
  EXPECT_EQ(LinesOf(utf16(u"\u03b8,\u20ac,\U0001D703", true)),
            (Lines{"\xCE\xB8,\xE2\x82\xAC,\xF0\x9D\x9C\x83"}));
  std::string error;
  LinesOf(utf16(u"ok\n", true) + std::string("\x00\xDC", 2), &error);  // a low surrogate alone
  EXPECT_NE(error.find("text_test_lines.txt:2: broken UTF-16 text"), std::string::npos) << error;
  LinesOf(std::string("\xFF\xFE\0\0t\0\0\0", 8), &error);
  EXPECT_NE(error.find("the file is UTF-32 text (its byte-order mark is \\xFF\\xFE\\x00\\x00)"),
            std::string::npos)
      << error;
  LinesOf(std::string("\0\0\xFE\xFF\0\0\0t", 8), &error);  // big-endian
  EXPECT_NE(error.find("the file is UTF-32 text (its byte-order mark is \\x00\\x00\\xFE\\xFF)"),
            std::string::npos)
      << error;
}

TEST(Text, ALineLongerThanTheBoundEndsTheLines) {
  std::string error;
  EXPECT_EQ(LinesOf("short\n" + std::string(100, 'x') + "\nafter\n", &error, 64), (Lines{"short"}));
  EXPECT_NE(error.find("text_test_lines.txt:2: line longer than 64 bytes"), std::string::npos)
      << error;
  EXPECT_EQ(LinesOf(std::string(64, 'x'), &error, 64), (Lines{std::string(64, 'x')}));
  EXPECT_EQ(error, "");
}

// A file of endless short lines (`yes 0,0,0,0 |`) would grow a reader's rows until it was
// killed: the number of lines is bounded too, and a file of exactly that many is whole.
TEST(Text, MoreLinesThanTheBoundEndTheLines) {
  std::string error;
  EXPECT_EQ(LinesOf("a\nb\r\nc\n", &error, kMaxTextLineBytes, 3), (Lines{"a", "b", "c"}));
  EXPECT_EQ(error, "");
  EXPECT_EQ(LinesOf("a\nb\nc", &error, kMaxTextLineBytes, 3), (Lines{"a", "b", "c"}));
  EXPECT_EQ(error, "");
  EXPECT_EQ(LinesOf("a\nb\nc\n\n", &error, kMaxTextLineBytes, 3), (Lines{"a", "b", "c"}));
  EXPECT_NE(error.find("text_test_lines.txt: more than 3 lines, the most read from one file"),
            std::string::npos)
      << error;
}

// Issue 34's sweep: `camcal --points /dev/zero` grew to 11.8 GB in 30 s: a file that never
// ends a line is refused at the bound, and a folder is named.
TEST(Text, EndlessFilesAndFoldersAreRefused) {
  TextLines zero("/dev/zero", "points file");
  std::string line;
  EXPECT_FALSE(zero.Next(&line));
  EXPECT_EQ(zero.status().message(),
            "/dev/zero:1: line longer than 65536 bytes: not a text file of this kind");
  const std::string dir = std::filesystem::temp_directory_path().string();
  TextLines folder(dir, "points file");
  EXPECT_FALSE(folder.Next(&line));
  EXPECT_EQ(folder.status().message(), dir + ": cannot open points file: Is a directory");
  TextLines missing(dir + "/kincal_no_such_file.csv", "poses CSV");
  EXPECT_FALSE(missing.Next(&line));
  EXPECT_EQ(missing.status().message(),
            dir + "/kincal_no_such_file.csv: cannot open poses CSV: No such file or directory");
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
  // The parser sees plain text: no mark, LF endings.
  EXPECT_EQ(read.value(), "a: 1\nb: [2, 3]\n" + std::string(40000, '#') + "\n");

  const StatusOr<std::string> small = ReadTextFile(path, "layout", 1000);
  ASSERT_FALSE(small.ok());
  EXPECT_EQ(small.status().message(), path + ": layout larger than 1000 bytes: not read");

  // A file read whole is bounded by its bytes, never by the line reader's count of lines:
  // more blank lines than kMaxTextLines within 16 MiB are read, and past the bytes the size
  // is what is said.
  const std::string blank(static_cast<size_t>(kMaxTextLines) + 1, '\n');
  {
    std::ofstream out(path, std::ios::binary);
    out << blank;
  }
  const StatusOr<std::string> lines = ReadTextFile(path, "layout");
  ASSERT_TRUE(lines.ok()) << lines.status().message();
  EXPECT_EQ(lines.value(), blank);
  EXPECT_EQ(ReadTextFile(path, "layout", 100).status().message(),
            path + ": layout larger than 100 bytes: not read");

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
