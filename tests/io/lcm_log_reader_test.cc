// The bounded LCM log reader: reads what liblcm writes, names a cut-short last event and
// skips damage, saying at which byte offset.
#include "kincal/io/lcm_log_reader.h"

#include <gtest/gtest.h>

#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>

#include "io/io_test_util.h"
#include "kincal/io/recording.h"

namespace kincal {
namespace {

using testing::OpenLog;
using testing::ReadAll;
using testing::ThreeEventLog;
class LcmLogReaderTest : public testing::IoTest {};

TEST_F(LcmLogReaderTest, ReadsWhatLiblcmWrites) {
  std::vector<int64_t> off;
  const std::string bytes = ThreeEventLog(dir_, &off);
  ASSERT_EQ(bytes.size(), static_cast<size_t>(off[2] + 28 + 3 + 102));
  const auto opened = OpenLog((dir_ / "three.lcm").string());
  ASSERT_NE(opened, nullptr);
  LcmLogReader& r = *opened;
  const auto ev = ReadAll(r);
  ASSERT_EQ(ev.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(ev[k].channel, "CH" + std::to_string(k));
    EXPECT_EQ(ev[k].timestamp, 1000 + k);
    EXPECT_EQ(ev[k].offset, off[k]);
    EXPECT_EQ(ev[k].data,
              std::vector<uint8_t>(static_cast<size_t>(100 + k), static_cast<uint8_t>(k)));
  }
  EXPECT_EQ(r.damaged_bytes(), 0);
  EXPECT_FALSE(r.truncated());
  EXPECT_TRUE(r.problems().empty());
  r.Rewind();
  EXPECT_EQ(ReadAll(r).size(), 3u);
  // What cannot be read is named, with why (errno's text), and nothing is opened.
  std::unique_ptr<LcmLogReader> none;
  const std::string missing = (dir_ / "none.lcm").string();
  Status s = LcmLogReader::Open(missing, &none);
  EXPECT_EQ(s.message(), missing + ": cannot open the LCM log: No such file or directory");
  EXPECT_EQ(none, nullptr);
  s = LcmLogReader::Open(dir_.string(), &none);
  EXPECT_EQ(s.message(), dir_.string() + ": is a directory, expected an LCM log file");
  EXPECT_EQ(none, nullptr);
}

TEST_F(LcmLogReaderTest, NamesACutShortLastEvent) {
  std::vector<int64_t> off;
  const std::string bytes = ThreeEventLog(dir_, &off);
  for (const size_t cut : {static_cast<size_t>(off[2] + 10), static_cast<size_t>(off[2] + 40)}) {
    const std::string p = Write("cut.lcm", bytes.substr(0, cut));
    const auto opened = OpenLog(p);
    ASSERT_NE(opened, nullptr);
    LcmLogReader& r = *opened;
    EXPECT_EQ(ReadAll(r).size(), 2u) << cut;
    EXPECT_TRUE(r.truncated());
    ASSERT_EQ(r.problems().size(), 1u);
    EXPECT_NE(r.problems()[0].find("byte " + std::to_string(off[2])), std::string::npos)
        << r.problems()[0];
    EXPECT_NE(r.problems()[0].find("cut short"), std::string::npos) << r.problems()[0];
  }
}

TEST_F(LcmLogReaderTest, SkipsDamageAndSaysWhere) {
  std::vector<int64_t> off;
  const std::string bytes = ThreeEventLog(dir_, &off);
  {  // A data length of 2^31 - 1 in the middle event: no allocation, skip to the third.
    std::string b = bytes;
    for (int i = 0; i < 4; ++i) b[static_cast<size_t>(off[1] + 24 + i)] = i == 0 ? '\x7f' : '\xff';
    const auto opened = OpenLog(Write("huge.lcm", b));
    ASSERT_NE(opened, nullptr);
    LcmLogReader& r = *opened;
    const auto ev = ReadAll(r);
    ASSERT_EQ(ev.size(), 2u);
    EXPECT_EQ(ev[0].channel, "CH0");
    EXPECT_EQ(ev[1].channel, "CH2");
    EXPECT_EQ(r.damaged_stretches(), 1);
    EXPECT_EQ(r.damaged_bytes(), off[2] - off[1]);
    EXPECT_FALSE(r.truncated());
    ASSERT_EQ(r.problems().size(), 1u);
    EXPECT_NE(r.problems()[0].find("byte " + std::to_string(off[1])), std::string::npos)
        << r.problems()[0];
  }
  {  // Seven junk bytes between the first and second events.
    std::string b = bytes;
    b.insert(static_cast<size_t>(off[1]), "garbage");
    const auto opened = OpenLog(Write("junk.lcm", b));
    ASSERT_NE(opened, nullptr);
    LcmLogReader& r = *opened;
    EXPECT_EQ(ReadAll(r).size(), 3u);
    EXPECT_EQ(r.damaged_bytes(), 7);
    EXPECT_EQ(r.damaged_stretches(), 1);
    ASSERT_EQ(r.problems().size(), 1u);
    EXPECT_NE(r.problems()[0].find("sync word"), std::string::npos) << r.problems()[0];
  }
}

}  // namespace
}  // namespace kincal
