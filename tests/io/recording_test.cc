// Recordings: CSV and MR.CLAM readers give errors naming the file, the line and what was
// expected, and count repeated times (kincald's LCM logs: lcm_log_test.cc).
#include "kincal/io/recording.h"

#include <gtest/gtest.h>

#include "io/io_test_util.h"
#include "windows_text.h"

namespace kincal {
namespace {

class RecordingCsv : public testing::IoTest {};

const char* kPoses = "t,x,y,theta\n0,0,0,0\n1,1,0,0\n2,2,0,0\n";

TEST_F(RecordingCsv, MissingColumnNamesFileLineAndExpectedHeader) {
  const std::string e = Error("t,v\n0,1\n", kPoses);
  EXPECT_NE(e.find("c.csv:1: the header 't,v' lacks column 'omega' (expected header 't,v,omega')"),
            std::string::npos)
      << e;
}

// A spreadsheet saved with semicolons (a decimal-comma locale) or tabs: the separator is
// named (it read "header lacks column 't'", though the header starts with t).
TEST_F(RecordingCsv, ASemicolonOrTabSeparatedFileIsNamedAsSuch) {
  const std::string semi = Error("t;v;omega\n0;0.5;0.1\n", kPoses);
  EXPECT_NE(semi.find("c.csv:1: the header 't;v;omega' has no comma; kincal reads "
                      "comma-separated values and this file's look separated by ';'"),
            std::string::npos)
      << semi;
  const std::string tab = Error("t\tv\tomega\n0\t0.5\t0.1\n", kPoses);
  EXPECT_NE(tab.find("c.csv:1: the header 't\\tv\\tomega' has no comma"), std::string::npos) << tab;
}

TEST_F(RecordingCsv, NonNumericValueNamesLineAndColumn) {
  const std::string e = Error("t,v,omega\n0,1,0\n1,fast,0\n", kPoses);
  EXPECT_NE(e.find("c.csv:3: column 'v': expected a finite number, got 'fast'"), std::string::npos)
      << e;
}

// Issue 34: files from Windows tools (CRLF) and spreadsheets (a UTF-8 byte-order mark) read
// as their LF twins, and so do a lone CR's (Excel for Mac's "CSV (Macintosh)": it read as
// one line, "column '0' appears twice") and UTF-16's (a spreadsheet's "Unicode text": "header
// lacks column 't'"); what is invisible in a bad token is shown escaped.
TEST_F(RecordingCsv, CrlfAndByteOrderMarkReadAsPlainText) {
  const auto model = MakeModel("unicycle").value();
  const std::string c = "t,v,omega\n0,1,0\n1,1,0.5\n2,1,0\n";
  const std::string p = "t,x,y,theta\n0,0,0,0\n1,1,0,0\n2,2,0.1,0.2\n";
  const Recording plain = ReadCsvRecording(Write("c.csv", c), Write("p.csv", p), *model).value();
  const auto cs = testing::OtherSystemsText(c);
  const auto ps = testing::OtherSystemsText(p);
  for (size_t i = 0; i < cs.size(); ++i) {
    const char* system = cs[i].first;
    const StatusOr<Recording> win =
        ReadCsvRecording(Write("cw.csv", cs[i].second), Write("pw.csv", ps[i].second), *model);
    ASSERT_TRUE(win.ok()) << system << ": " << win.status().message();
    ASSERT_EQ(win->poses.size(), plain.poses.size()) << system;
    for (size_t k = 0; k < plain.poses.size(); ++k) {
      EXPECT_EQ(win->poses[k].t_ns, plain.poses[k].t_ns) << system;
      EXPECT_EQ(win->poses[k].z, plain.poses[k].z) << system;
    }
    ASSERT_EQ(win->controls.size(), plain.controls.size()) << system;
    EXPECT_EQ(win->controls.ValuesAt(1)[1], 0.5) << system;
  }
  // An invisible character in a value (a spreadsheet's no-break space) is named, escaped.
  const std::string e = Error("t,v,omega\n0,1\xC2\xA0,0\n1,1,0\n", kPoses);
  EXPECT_NE(e.find("c.csv:2: column 'v': expected a finite number, got '1\\xC2\\xA0'"),
            std::string::npos)
      << e;
}

TEST_F(RecordingCsv, MrclamFilesWithCrlfAndByteOrderMark) {
  const std::string d = dir_.string();
  const auto gt = testing::OtherSystemsText("# comment\n10.0 1 2 0.5\n10.2 1.01 2 0.5\n");
  size_t k = 0;
  for (const auto& [system, text] :
       testing::OtherSystemsText("# Time [sec]\n10.0 0.1 0\n10.1 0.1 0.2\n")) {
    Write("Robot1_Odometry.dat", text);
    Write("Robot1_Groundtruth.dat", gt[k++].second);
    const StatusOr<Recording> r = ReadMrclam(d, 1);
    ASSERT_TRUE(r.ok()) << system << ": " << r.status().message();
    EXPECT_EQ(r->stats.comment_lines, 2) << system;
    EXPECT_EQ(r->controls.size(), 2u) << system;
    EXPECT_EQ(r->poses.size(), 2u) << system;
  }
}

// Issue 34's sweep: a spreadsheet or pandas saving with every field quoted, and C's "%+g",
// read as their plain twins; what follows a closing quote is named.
TEST_F(RecordingCsv, QuotedFieldsAndPlusSignsAreNumbers) {
  const auto model = MakeModel("unicycle").value();
  const StatusOr<Recording> r = ReadCsvRecording(
      Write("c.csv", "\"t\",\"v\",\"omega\"\n\"0\",\"1\",\"0\"\n\"1\",\"+1\",\"+0.5\"\n"),
      Write("p.csv", "t,x,y,theta\n+0,+0,-0,0\n+1,+1.5e+0,0,0\n"), *model);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->controls.ValuesAt(1)[1], 0.5);
  EXPECT_EQ(r->poses[1].z.x(), 1.5);
  EXPECT_NE(Error("t,v,omega\n0,\"1\"m,0\n1,1,0\n", kPoses)
                .find("c.csv:2: column 'v': expected a finite number, got '1m'"),
            std::string::npos);
  // A header the reader cannot use is shown as it was read.
  EXPECT_NE(Error("t,v,om\xC3\xA9ga\n0,1,0\n", kPoses)
                .find("c.csv:1: the header 't,v,om\\xC3\\xA9ga' lacks column 'omega'"),
            std::string::npos);
}

TEST_F(RecordingCsv, TimeGoingBackwardsIsAnError) {
  const std::string e = Error("t,v,omega\n0,1,0\n2,1,0\n1,1,0\n", kPoses);
  EXPECT_NE(e.find("c.csv:4: time 1 goes backwards (previous row, line 3, has 2)"),
            std::string::npos)
      << e;
}

TEST_F(RecordingCsv, DisjointSpansAreAnError) {
  const std::string e = Error("t,v,omega\n100,1,0\n101,1,0\n", kPoses);
  EXPECT_NE(e.find("time spans do not overlap"), std::string::npos) << e;
}

// Issue 16: every number read is range-checked, naming the file, line and column. Beyond
// these, a time overflowed the nanosecond time base.
TEST_F(RecordingCsv, ImplausibleValuesNameTheirColumnAndUnit) {
  EXPECT_NE(Error("t,v,omega\n0,1,0\n1,1,1e300\n", kPoses)
                .find("c.csv:3: column 'omega': 1e+300 is beyond +-10000 (rad/s)"),
            std::string::npos);
  EXPECT_NE(Error("t,v,omega\n0,5000,0\n1,1,0\n", kPoses)
                .find("c.csv:2: column 'v': 5000 is beyond +-1000 (m/s)"),
            std::string::npos);
  EXPECT_NE(Error("t,v,omega\n0,1,0\n1e300,1,0\n", kPoses)
                .find("c.csv:3: column 't': 1e+300 is beyond +-10000000000 (seconds; a time in "
                      "milliseconds or nanoseconds is this large)"),
            std::string::npos);
  EXPECT_NE(Error("t,v,omega\n0,1,0\n2,1,0\n", "t,x,y,theta\n0,0,0,0\n1,2e9,0,0\n")
                .find("p.csv:3: column 'x': 2000000000 is beyond +-1000000 (metres)"),
            std::string::npos);
}

TEST_F(RecordingCsv, EmptyFileAndWrongRowLength) {
  EXPECT_NE(Error("", kPoses).find("c.csv: empty file (no header)"), std::string::npos);
  EXPECT_NE(Error("t,v,omega\n0,1\n", kPoses).find("c.csv:2: expected 3 values, found 2"),
            std::string::npos);
  EXPECT_NE(Error("t,v,omega\n", kPoses).find("c.csv: no control rows"), std::string::npos);
}

// Reproduces issue 16 (items 9 and 13): a directory given as a CSV said "empty file", and
// --poses /dev/zero read one endless line (3.9 GB in 10 s).
TEST_F(RecordingCsv, DirectoriesAndEndlessLinesAreNamed) {
  std::string e =
      ReadCsvRecording(dir_.string(), Write("p.csv", kPoses), *MakeModel("unicycle").value())
          .status()
          .message();
  EXPECT_NE(e.find(": cannot open recording file: Is a directory"), std::string::npos) << e;
  e = ReadCsvRecording(Write("c.csv", "t,v,omega\n0,1,0\n"), "/dev/zero",
                       *MakeModel("unicycle").value())
          .status()
          .message();
  EXPECT_NE(e.find("/dev/zero:1: line longer than 65536 bytes"), std::string::npos) << e;
}

// A recording is held in memory whole: a file of endless valid lines (`yes 0,0,0,0 |`) grew
// until it was killed. Reading stops at the configured bound, naming the file and how to
// raise it; a file of exactly that many lines is read.
TEST_F(RecordingCsv, MoreLinesThanTheBoundAreRefused) {
  const auto model = MakeModel("unicycle").value();
  RecordingLimits limits;
  limits.max_rows = 4;  // kPoses: a header and three rows
  const std::string poses = Write("p.csv", kPoses);
  const std::string controls = Write("c.csv", "t,v,omega\n0,1,0\n1,1,0\n2,1,0\n");
  EXPECT_TRUE(ReadCsvRecording(controls, poses, *model, false, limits).ok());
  limits.max_rows = 3;
  const std::string e = ReadCsvRecording(controls, poses, *model, false, limits).status().message();
  EXPECT_EQ(e, controls +
                   ": more than 3 lines, the most read from one file (a recording is held in "
                   "memory whole; kincal analyze --max-rows raises the bound)");
  Write("Robot1_Odometry.dat", "# t v w\n0 1 0\n1 1 0\n2 1 0\n");
  Write("Robot1_Groundtruth.dat", "0 0 0 0\n1 1 0 0\n2 2 0 0\n");
  limits.max_rows = 4;
  EXPECT_TRUE(ReadMrclam(dir_.string(), 1, limits).ok());  // a comment is a line too
  limits.max_rows = 3;
  EXPECT_NE(ReadMrclam(dir_.string(), 1, limits)
                .status()
                .message()
                .find("Robot1_Odometry.dat: more than 3 lines"),
            std::string::npos);
  limits.max_rows = 0;
  EXPECT_EQ(ReadCsvRecording(controls, poses, *model, false, limits).status().message(),
            "max_rows 0: expected 1 or more");
  EXPECT_EQ(ReadMrclam(dir_.string(), 1, limits).status().message(),
            "max_rows 0: expected 1 or more");
}

// A motion-capture export leaves a frame's fields empty (Vicon, OptiTrack) or NaN (pandas)
// while the tracker has lost the robot: each such row used to stop the read ("expected a
// finite number, got ''"). It is no measurement: skipped, counted and said. A row with some
// of its pose and not the rest is still an error naming the column.
TEST_F(RecordingCsv, PoseRowsTheTrackerLostAreSkippedAndSaid) {
  const auto model = MakeModel("unicycle").value();
  const std::string controls = Write("c.csv", "t,v,omega\n0,1,0\n2,1,0\n");
  const Recording r =
      ReadCsvRecording(controls,
                       Write("p.csv",
                             "t,x,y,theta\n0,0,0,0\n0.5,,,\n1,NaN,NaN,nan\n1.5,1.5,0,0\n"
                             "2,2,0,0\n"),
                       *model)
          .value();
  EXPECT_EQ(r.poses.size(), 3u);
  EXPECT_EQ(r.stats.pose_rows, 3);
  EXPECT_EQ(r.stats.pose_rows_lost, 2);
  EXPECT_NEAR(r.poses[1].z.x(), 1.5, 1e-12);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("p.csv: 2 rows have no pose (every pose field empty or NaN: the "
                               "tracker lost the robot) and were skipped; the longest stretch "
                               "without a pose is 1.5 s, from line 2 to line 5"),
            std::string::npos)
      << r.warnings[0];
  EXPECT_EQ(Error("t,v,omega\n0,1,0\n", "t,x,y,theta\n0,0,0,0\n1,1,,0\n"),
            dir_.string() + "/p.csv:3: column 'y': expected a finite number, got ''");
  EXPECT_EQ(Error("t,v,omega\n0,1,0\n", "t,x,y,theta\n0,,,\n1,nan,nan,nan\n"),
            dir_.string() + "/p.csv: no pose rows: every row's pose is empty or NaN");
  // Controls have no such rows: a missing control is an error.
  EXPECT_NE(Error("t,v,omega\n0,,\n1,1,0\n", kPoses).find("c.csv:2: column 'v'"),
            std::string::npos);
}

TEST_F(RecordingCsv, RepeatedTimesAreCountedAndColumnOrderIsFree) {
  const Recording r = ReadCsvRecording(Write("c.csv", "omega,t,v\n0,0,1\n0.5,0,2\n0,1,3\n"),
                                       Write("p.csv", "t,theta,x,y\n0,0,0,0\n0,0.1,0,0\n1,0,1,0\n"),
                                       *MakeModel("unicycle").value())
                          .value();
  EXPECT_EQ(r.stats.control_repeated_times, 1);
  EXPECT_EQ(r.stats.pose_repeated_times, 1);
  EXPECT_EQ(r.controls.At(0.5)[0], 2.0);  // v, the later of the repeated rows
  EXPECT_EQ(r.controls.At(0.5)[1], 0.5);  // omega
  EXPECT_EQ(r.poses.size(), 2u);
  EXPECT_NEAR(r.poses[0].z.z(), 0.1, 1e-15);
  // Both repeats carry other values than the row before them: said, not only counted
  // (a 0.5 m jump at one time was once a silent "1 repeated time").
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_NE(r.warnings[0].find("c.csv: line 3 repeats the time of line 2 (0 s from the start) "
                               "with other values (2,0.5 against 1,0)"),
            std::string::npos)
      << r.warnings[0];
  EXPECT_NE(r.warnings[1].find("p.csv: line 3 repeats the time of line 2"), std::string::npos)
      << r.warnings[1];
  // The same row twice is a copy: counted, not said.
  const Recording copies = ReadCsvRecording(Write("c.csv", "t,v,omega\n0,1,0\n0,1,0\n1,1,0\n"),
                                            Write("p.csv", kPoses), *MakeModel("unicycle").value())
                               .value();
  EXPECT_EQ(copies.stats.control_repeated_times, 1);
  EXPECT_TRUE(copies.warnings.empty());
}

TEST_F(RecordingCsv, HeadingInDegreesIsFlagged) {
  const Recording r = ReadCsvRecording(Write("c.csv", "t,v,omega\n0,1,0\n1,1,0\n"),
                                       Write("p.csv", "t,x,y,theta\n0,0,0,90\n1,1,0,180\n"),
                                       *MakeModel("unicycle").value())
                          .value();
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("theta reaches 180; kincal expects radians"), std::string::npos)
      << r.warnings[0];
}

// Issue 34's sweep: a car's steering written in degrees (25 for 25 degrees) was read as
// 25 rad with nothing said; like a heading in degrees, it is now flagged.
TEST_F(RecordingCsv, SteeringInDegreesIsFlagged) {
  const auto bicycle = MakeModel("bicycle").value();
  const Recording r = ReadCsvRecording(Write("c.csv", "t,v,steer\n0,1,0\n1,1,25\n2,1,-12\n"),
                                       Write("p.csv", kPoses), *bicycle)
                          .value();
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("c.csv: column 'steer' reaches 25; kincal expects a steering angle "
                               "in radians"),
            std::string::npos)
      << r.warnings[0];
  const Recording ok = ReadCsvRecording(Write("c.csv", "t,v,steer\n0,1,0\n1,1,0.4\n2,1,-0.6\n"),
                                        Write("p.csv", kPoses), *bicycle)
                           .value();
  EXPECT_TRUE(ok.warnings.empty());
}

TEST_F(RecordingCsv, MrclamCommentsAndMissingFile) {
  const std::string d = dir_.string();
  Write("Robot1_Odometry.dat", "# comment\n10.0 0.1 0.0\n10.5 0.1 0.2\n");
  Write("Robot1_Groundtruth.dat", "# comment\n10.0 1 2 0.5\n10.2 1.01 2 0.5\n");
  const Recording r = ReadMrclam(d, 1).value();
  EXPECT_EQ(r.stats.comment_lines, 2);
  EXPECT_EQ(r.origin_s, 10.0);
  EXPECT_EQ(r.controls.size(), 2u);
  const StatusOr<Recording> missing = ReadMrclam(d, 2);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("Robot2_Odometry.dat: cannot open"), std::string::npos)
      << missing.status().message();
}

}  // namespace
}  // namespace kincal
