// CleanLine and Escaped (src/core/text.cc): CRLF and a byte-order mark taken, invisible
// characters shown.
#include "kincal/text.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace kincal
