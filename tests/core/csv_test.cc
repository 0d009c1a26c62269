// SplitCsvFields and ParseFiniteNumber (src/core/csv.cc): fields as spreadsheets and scripts
// write them, quoted or not, and numbers with a '+'.
#include "kincal/csv.h"

#include <gtest/gtest.h>

#include <limits>

namespace kincal {
namespace {

using Fields = std::vector<std::string>;

TEST(Csv, PlainFieldsLoseTheBlanksAroundThem) {
  EXPECT_EQ(SplitCsvFields("t,x,y,theta"), (Fields{"t", "x", "y", "theta"}));
  EXPECT_EQ(SplitCsvFields(" t , x\t,y "), (Fields{"t", "x", "y"}));
  EXPECT_EQ(SplitCsvFields("1,,2,"), (Fields{"1", "", "2", ""}));
  EXPECT_EQ(SplitCsvFields(""), (Fields{""}));
}

// A spreadsheet saving with "quote all fields", or pandas with quoting=QUOTE_ALL, writes
// "t","x": issue 34's sweep found such a header read as lacking column 't'.
TEST(Csv, QuotedFieldsLoseTheirQuotes) {
  EXPECT_EQ(SplitCsvFields("\"t\",\"x\",\"y\",\"theta\""), (Fields{"t", "x", "y", "theta"}));
  EXPECT_EQ(SplitCsvFields(" \"0.5\" , \"1\""), (Fields{"0.5", "1"}));
  // RFC 4180: a doubled quote is one quote; a comma inside quotes is the field's own.
  EXPECT_EQ(SplitCsvFields("\"a \"\"b\"\"\",\"1,5\",2"), (Fields{"a \"b\"", "1,5", "2"}));
  EXPECT_EQ(SplitCsvFields("\" padded \",x"), (Fields{" padded ", "x"}));
  // What follows a closing quote stays, so the number check names it; so does an open quote.
  EXPECT_EQ(SplitCsvFields("\"1.5\"x,2"), (Fields{"1.5x", "2"}));
  EXPECT_EQ(SplitCsvFields("1,\"2,3"), (Fields{"1", "2,3"}));
  // A quote inside an unquoted field is kept, not taken for a quoted field.
  EXPECT_EQ(SplitCsvFields("5\"2,1"), (Fields{"5\"2", "1"}));
}

TEST(Csv, NumbersAreFiniteAndWrittenInFull) {
  double v = 0.0;
  EXPECT_TRUE(ParseFiniteNumber("237.257", &v));
  EXPECT_EQ(v, 237.257);
  EXPECT_TRUE(ParseFiniteNumber("+1.5e-3", &v));  // C's "%+g"
  EXPECT_EQ(v, 1.5e-3);
  EXPECT_TRUE(ParseFiniteNumber("-2", &v));
  EXPECT_EQ(v, -2.0);
  EXPECT_TRUE(ParseFiniteNumber(".5", &v));
  EXPECT_EQ(v, 0.5);
  for (const char* bad : {"", "+", "++1", "+-1", "1.5\r", " 1", "1 ", "0x10", "1,5", "nan", "inf",
                          "-inf", "1e999", "abc"}) {
    EXPECT_FALSE(ParseFiniteNumber(bad, &v)) << bad;
  }
}

}  // namespace
}  // namespace kincal
