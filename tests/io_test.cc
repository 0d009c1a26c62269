// Readers: bad input gets an error naming the file, the line and what was expected;
// repeated times are counted, not silently dropped; a kincald LCM log reads back.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "kincal/analysis/analyze.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/io/recording.h"

namespace kincal {
namespace {

// Appends one encoded LCM message to a log written with liblcm's own writer.
template <typename Msg>
void PutMessage(lcm::LogFile& log, const std::string& channel, const Msg& msg, int64_t utime) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent ev{};
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(buf.size());
  ev.data = buf.data();
  log.writeEvent(&ev);
}

class Io : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("kincal_io_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    const auto p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  std::string Error(const std::string& controls, const std::string& poses) {
    try {
      ReadCsvRecording(Write("c.csv", controls), Write("p.csv", poses), *MakeModel("unicycle"));
    } catch (const RecordingError& e) {
      return e.what();
    }
    return "no error";
  }
  std::filesystem::path dir_;
};

const char* kPoses = "t,x,y,theta\n0,0,0,0\n1,1,0,0\n2,2,0,0\n";

TEST_F(Io, MissingColumnNamesFileLineAndExpectedHeader) {
  const std::string e = Error("t,v\n0,1\n", kPoses);
  EXPECT_NE(e.find("c.csv:1: header lacks column 'omega' (expected header 't,v,omega')"),
            std::string::npos)
      << e;
}

TEST_F(Io, NonNumericValueNamesLineAndColumn) {
  const std::string e = Error("t,v,omega\n0,1,0\n1,fast,0\n", kPoses);
  EXPECT_NE(e.find("c.csv:3: column 'v': expected a finite number, got 'fast'"), std::string::npos)
      << e;
}

TEST_F(Io, TimeGoingBackwardsIsAnError) {
  const std::string e = Error("t,v,omega\n0,1,0\n2,1,0\n1,1,0\n", kPoses);
  EXPECT_NE(e.find("c.csv:4: time 1 goes backwards (previous row, line 3, has 2)"),
            std::string::npos)
      << e;
}

TEST_F(Io, DisjointSpansAreAnError) {
  const std::string e = Error("t,v,omega\n100,1,0\n101,1,0\n", kPoses);
  EXPECT_NE(e.find("time spans do not overlap"), std::string::npos) << e;
}

TEST_F(Io, EmptyFileAndWrongRowLength) {
  EXPECT_NE(Error("", kPoses).find("c.csv: empty file (no header)"), std::string::npos);
  EXPECT_NE(Error("t,v,omega\n0,1\n", kPoses).find("c.csv:2: expected 3 values, found 2"),
            std::string::npos);
  EXPECT_NE(Error("t,v,omega\n", kPoses).find("c.csv: no control rows"), std::string::npos);
}

TEST_F(Io, RepeatedTimesAreCountedAndColumnOrderIsFree) {
  const Recording r = ReadCsvRecording(Write("c.csv", "omega,t,v\n0,0,1\n0.5,0,2\n0,1,3\n"),
                                       Write("p.csv", "t,theta,x,y\n0,0,0,0\n0,0.1,0,0\n1,0,1,0\n"),
                                       *MakeModel("unicycle"));
  EXPECT_EQ(r.stats.control_repeated_times, 1);
  EXPECT_EQ(r.stats.pose_repeated_times, 1);
  EXPECT_EQ(r.controls.At(0.5)[0], 2.0);  // v, the later of the repeated rows
  EXPECT_EQ(r.controls.At(0.5)[1], 0.5);  // omega
  EXPECT_EQ(r.poses.size(), 2u);
  EXPECT_NEAR(r.poses[0].z.z(), 0.1, 1e-15);
}

TEST_F(Io, HeadingInDegreesIsFlagged) {
  const Recording r = ReadCsvRecording(Write("c.csv", "t,v,omega\n0,1,0\n1,1,0\n"),
                                       Write("p.csv", "t,x,y,theta\n0,0,0,90\n1,1,0,180\n"),
                                       *MakeModel("unicycle"));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("theta reaches 180; kincal expects radians"), std::string::npos)
      << r.warnings[0];
}

TEST_F(Io, MrclamCommentsAndMissingFile) {
  const std::string d = dir_.string();
  Write("Robot1_Odometry.dat", "# comment\n10.0 0.1 0.0\n10.5 0.1 0.2\n");
  Write("Robot1_Groundtruth.dat", "# comment\n10.0 1 2 0.5\n10.2 1.01 2 0.5\n");
  const Recording r = ReadMrclam(d, 1);
  EXPECT_EQ(r.stats.comment_lines, 2);
  EXPECT_EQ(r.origin_s, 10.0);
  EXPECT_EQ(r.controls.size(), 2u);
  try {
    ReadMrclam(d, 2);
    FAIL();
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("Robot2_Odometry.dat: cannot open"), std::string::npos)
        << e.what();
  }
}

TEST_F(Io, LcmLogReadsBack) {
  const std::string path = (dir_ / "run.lcm").string();
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    for (int k = 0; k < 5; ++k) {
      kincal::controls_t c{};
      c.schema_version = 1;
      c.utime = 1'000'000 + k * 100'000;
      c.model = "unicycle";
      c.num_controls = 2;
      c.names = {"omega", "v"};
      c.values = {0.1 * k, 0.5};
      PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = 1'000'000 + k * 100'000 + 50'000;
      p.x = 0.05 * k;
      p.valid = 1;
      PutMessage(log, "KINCAL_POSE", p, p.utime);
    }
  }
  const Recording r = ReadLcmLog(path, *MakeModel("unicycle"));
  EXPECT_EQ(r.controls.size(), 5u);
  EXPECT_EQ(r.poses.size(), 5u);
  EXPECT_DOUBLE_EQ(r.origin_s, 1.0);
  EXPECT_EQ(r.controls.At(0.45)[0], 0.5);           // v, mapped by name
  EXPECT_NEAR(r.controls.At(0.45)[1], 0.4, 1e-12);  // omega
  EXPECT_NEAR(r.poses[2].z.x(), 0.1, 1e-12);
  EXPECT_THROW(ReadLcmLog((dir_ / "none.lcm").string(), *MakeModel("unicycle")), RecordingError);
}

// Three events written by liblcm's own writer; the bytes of the file, for damaging.
std::string ThreeEventLog(const std::filesystem::path& dir, std::vector<int64_t>* offsets) {
  const std::string path = (dir / "three.lcm").string();
  {
    lcm::LogFile log(path, "w");
    for (int k = 0; k < 3; ++k) {
      std::vector<uint8_t> data(static_cast<size_t>(100 + k), static_cast<uint8_t>(k));
      lcm::LogEvent ev{};
      ev.timestamp = 1000 + k;
      ev.channel = "CH" + std::to_string(k);
      ev.datalen = static_cast<int32_t>(data.size());
      ev.data = data.data();
      log.writeEvent(&ev);
    }
  }
  // Header 28 bytes + channel 3 bytes + data.
  *offsets = {0, 28 + 3 + 100, 2 * (28 + 3) + 100 + 101};
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<LcmLogEvent> ReadAll(LcmLogReader& r) {
  std::vector<LcmLogEvent> out;
  LcmLogEvent e;
  while (r.Next(&e)) out.push_back(e);
  return out;
}

TEST_F(Io, LcmLogReaderReadsWhatLiblcmWrites) {
  std::vector<int64_t> off;
  const std::string bytes = ThreeEventLog(dir_, &off);
  ASSERT_EQ(bytes.size(), static_cast<size_t>(off[2] + 28 + 3 + 102));
  LcmLogReader r((dir_ / "three.lcm").string());
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
  EXPECT_THROW(LcmLogReader((dir_ / "none.lcm").string()), std::runtime_error);
}

TEST_F(Io, LcmLogReaderNamesACutShortLastEvent) {
  std::vector<int64_t> off;
  const std::string bytes = ThreeEventLog(dir_, &off);
  for (const size_t cut : {static_cast<size_t>(off[2] + 10), static_cast<size_t>(off[2] + 40)}) {
    const std::string p = Write("cut.lcm", bytes.substr(0, cut));
    LcmLogReader r(p);
    EXPECT_EQ(ReadAll(r).size(), 2u) << cut;
    EXPECT_TRUE(r.truncated());
    ASSERT_EQ(r.problems().size(), 1u);
    EXPECT_NE(r.problems()[0].find("byte " + std::to_string(off[2])), std::string::npos)
        << r.problems()[0];
    EXPECT_NE(r.problems()[0].find("cut short"), std::string::npos) << r.problems()[0];
  }
}

TEST_F(Io, LcmLogReaderSkipsDamageAndSaysWhere) {
  std::vector<int64_t> off;
  const std::string bytes = ThreeEventLog(dir_, &off);
  {  // A data length of 2^31 - 1 in the middle event: no allocation, skip to the third.
    std::string b = bytes;
    for (int i = 0; i < 4; ++i) b[static_cast<size_t>(off[1] + 24 + i)] = i == 0 ? '\x7f' : '\xff';
    LcmLogReader r(Write("huge.lcm", b));
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
    LcmLogReader r(Write("junk.lcm", b));
    EXPECT_EQ(ReadAll(r).size(), 3u);
    EXPECT_EQ(r.damaged_bytes(), 7);
    EXPECT_EQ(r.damaged_stretches(), 1);
    ASSERT_EQ(r.problems().size(), 1u);
    EXPECT_NE(r.problems()[0].find("sync word"), std::string::npos) << r.problems()[0];
  }
}

TEST_F(Io, DamagedLcmLogIsReadWithWarnings) {
  // ReadLcmLog keeps the good events and reports the damage as warnings.
  const std::string path = (dir_ / "run.lcm").string();
  {
    lcm::LogFile log(path, "w");
    for (int k = 0; k < 4; ++k) {
      kincal::controls_t c{};
      c.schema_version = 1;
      c.utime = 1'000'000 + k * 100'000;
      c.model = "unicycle";
      c.num_controls = 2;
      c.names = {"v", "omega"};
      c.values = {0.5, 0.1};
      kincal::pose_t p{};
      p.schema_version = 1;
      p.utime = c.utime + 50'000;
      p.valid = 1;
      PutMessage(log, "KINCAL_CONTROLS", c, c.utime);
      PutMessage(log, "KINCAL_POSE", p, c.utime);
    }
  }
  std::ifstream in(path, std::ios::binary);
  std::string b(std::istreambuf_iterator<char>(in), {});
  in.close();
  Write("run.lcm", b.substr(0, b.size() - 5));  // the last pose cut short
  const Recording r = ReadLcmLog(path, *MakeModel("unicycle"));
  EXPECT_EQ(r.controls.size(), 4u);
  EXPECT_EQ(r.poses.size(), 3u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("cut short"), std::string::npos) << r.warnings[0];
}

TEST_F(Io, UnobservableParameterIsNamedWithTheMotionThatExcitesIt) {
  // A robot that only drives straight: k_omega cannot be identified.
  std::string c = "t,v,omega\n", p = "t,x,y,theta\n";
  for (int k = 0; k <= 600; ++k) {
    const double t = 0.05 * k;
    c += std::to_string(t) + ",0.5,0\n";
    p += std::to_string(t) + "," + std::to_string(0.45 * t) + ",0,0\n";
  }
  const Recording rec =
      ReadCsvRecording(Write("c.csv", c), Write("p.csv", p), *MakeModel("unicycle"));
  AnalyzeOptions o;
  o.model = "unicycle";
  o.effects_mode = "none";
  o.pose_sigma = Eigen::Vector2d(0.001, 0.001);
  try {
    Analyze(rec, o);
    FAIL() << "expected an unobservability error";
  } catch (const AnalysisError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("parameter 'k_omega' is not identifiable"), std::string::npos) << m;
    EXPECT_NE(m.find("excite it with turning"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace kincal
