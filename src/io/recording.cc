#include "kincal/io/recording.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>

#include "kincal/angles.h"
#include "kincal/csv.h"
#include "kincal/text.h"
#include "lost_poses.h"
#include "repeated_times.h"

namespace kincal {
namespace {

// What the readers below throw on bad input; caught in this file's public functions, which
// return it as a Status.
class ReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <typename F>
StatusOr<Recording> Catching(F&& read) {
  try {
    return read();
  } catch (const ReadError& e) {
    return Status::Error(e.what());
  }
}

struct Row {
  int line;
  double t;
  std::vector<double> v;
  long long run = 0;  // the optional 'run' column of a CSV
};

// The CSV column that numbers the runs of a recording (optional, in any position).
constexpr const char* kRunColumn = "run";

long long ParseRun(const std::string& tok, const std::string& where) {
  long long v = 0;
  const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (ec != std::errc() || p != tok.data() + tok.size()) {
    throw ReadError(where + ": column 'run': expected an integer run number, got '" + Escaped(tok) +
                    "'");
  }
  return v;
}

std::string Trim(std::string s) {
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

// The whitespace-separated tokens of an MR.CLAM line.
std::vector<std::string> SplitWhitespace(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  std::string tok;
  while (in >> tok) out.push_back(tok);
  return out;
}

double ParseNumber(const std::string& tok, const std::string& where, const std::string& what) {
  double v = 0.0;
  if (!ParseFiniteNumber(tok, &v)) {
    throw ReadError(where + ": " + what + ": expected a finite number, got '" + Escaped(tok) + "'");
  }
  return v;
}

// The lines of a text file; throws naming the file on what TextLines refuses.
class Lines {
 public:
  Lines(const std::string& path, int max_lines)
      : lines_(path, "recording file", kMaxTextLineBytes, max_lines) {}
  bool Next(std::string* line) {
    if (lines_.Next(line)) return true;
    if (lines_.too_many_lines()) {
      throw ReadError(lines_.status().message() + " (" + std::string(kMaxRowsAdvice) + ")");
    }
    if (!lines_.status().ok()) throw ReadError(lines_.status().message());
    return false;
  }
  int number() const { return lines_.line_number(); }

 private:
  TextLines lines_;
};

// The columns of `wanted` (after "t") in the header `cols`, and the optional run column
// (*run_col, -1 if none); throws naming a missing, repeated or unexpected column.
std::vector<int> HeaderOrder(const std::vector<std::string>& cols,
                             const std::vector<std::string>& wanted, const std::string& where,
                             int* run_col) {
  if (cols.size() == 1) {  // a spreadsheet's other separators: said, not "lacks column 't'"
    for (const char sep : {';', '\t', ' '}) {
      if (cols[0].find(sep) == std::string::npos) continue;
      throw ReadError(where + ": the header '" + Escaped(cols[0]) +
                      "' has no comma; kincal reads comma-separated values and this file's look "
                      "separated by '" +
                      Escaped(std::string(1, sep)) + "'");
    }
  }
  std::vector<int> order;
  std::map<std::string, int> index;
  for (size_t i = 0; i < cols.size(); ++i) {
    if (index.count(cols[i]))
      throw ReadError(where + ": column '" + Escaped(cols[i]) + "' appears twice");
    index[cols[i]] = static_cast<int>(i);
  }
  std::string expected = "t";
  for (const auto& w : wanted) expected += "," + w;
  std::vector<std::string> all = {"t"};
  all.insert(all.end(), wanted.begin(), wanted.end());
  if (index.count(kRunColumn)) *run_col = index[kRunColumn];
  for (const auto& w : all) {
    if (!index.count(w)) {
      std::string read;
      for (const auto& c : cols) read += (read.empty() ? "" : ",") + c;
      throw ReadError(where + ": the header '" + Escaped(read) + "' lacks column '" + w +
                      "' (expected header '" + expected + "')");
    }
    order.push_back(index[w]);
  }
  for (const auto& c : cols) {
    if (c != kRunColumn && std::find(all.begin(), all.end(), c) == all.end()) {
      throw ReadError(where + ": unexpected column '" + Escaped(c) + "' (expected header '" +
                      expected + "')");
    }
  }
  return order;
}

// Whether every value column (after 't') of a row is missing (IsMissingValue).
bool NoValues(const std::vector<std::string>& cols, const std::vector<int>& order) {
  for (size_t k = 1; k < order.size(); ++k)
    if (!IsMissingValue(cols[static_cast<size_t>(order[k])])) return false;
  return true;
}

// Reads a CSV with a header; returns rows with columns ordered as `wanted`, and a 'run'
// column's value when the file has one (*has_run). With `lost`, a row whose values are all
// missing is skipped and counted there.
std::vector<Row> ReadCsv(const std::string& path, const std::vector<std::string>& wanted,
                         int max_lines, bool* has_run, LostPoses* lost = nullptr) {
  Lines lines(path, max_lines);
  std::string line;
  std::vector<int> order;
  int run_col = -1;
  std::vector<Row> rows;
  while (lines.Next(&line)) {
    const int n = lines.number();
    line = Trim(line);
    if (line.empty() || line[0] == '#') continue;
    const auto cols = SplitCsvFields(line);
    const std::string where = path + ":" + std::to_string(n);
    if (order.empty()) {
      order = HeaderOrder(cols, wanted, where, &run_col);
      continue;
    }
    const size_t columns = order.size() + (run_col >= 0 ? 1 : 0);
    if (cols.size() != columns) {
      throw ReadError(where + ": expected " + std::to_string(columns) + " values, found " +
                      std::to_string(cols.size()));
    }
    Row r{n, 0.0, {}};
    r.t = ParseNumber(cols[static_cast<size_t>(order[0])], where, "column 't'");
    if (lost && NoValues(cols, order)) {
      lost->Lost();
      continue;
    }
    if (lost) lost->Kept(r.t, n);
    for (size_t k = 1; k < order.size(); ++k) {
      r.v.push_back(ParseNumber(cols[static_cast<size_t>(order[k])], where,
                                "column '" + wanted[k - 1] + "'"));
    }
    if (run_col >= 0) r.run = ParseRun(cols[static_cast<size_t>(run_col)], where);
    rows.push_back(std::move(r));
  }
  if (order.empty()) throw ReadError(path + ": empty file (no header)");
  *has_run = run_col >= 0;
  return rows;
}

// Whitespace-separated numeric rows with '#' comments (MR.CLAM .dat).
std::vector<Row> ReadDat(const std::string& path, int columns, int max_lines, int* comments) {
  Lines lines(path, max_lines);
  std::string line;
  std::vector<Row> rows;
  while (lines.Next(&line)) {
    const int n = lines.number();
    line = Trim(line);
    if (line.empty()) continue;
    if (line[0] == '#') {
      ++*comments;
      continue;
    }
    const auto cols = SplitWhitespace(line);
    const std::string where = path + ":" + std::to_string(n);
    if (static_cast<int>(cols.size()) != columns) {
      throw ReadError(where + ": expected " + std::to_string(columns) + " values, found " +
                      std::to_string(cols.size()));
    }
    Row r{n, ParseNumber(cols[0], where, "time"), {}};
    for (int k = 1; k < columns; ++k)
      r.v.push_back(
          ParseNumber(cols[static_cast<size_t>(k)], where, "value " + std::to_string(k + 1)));
    rows.push_back(std::move(r));
  }
  return rows;
}

// Seconds within +-1e10 (a Unix time to the year 2286, or seconds since a start), positions
// within 1000 km: anything else is a unit mistake or garbage, and would overflow the
// nanosecond time base.
constexpr double kMaxAbsTimeS = 1e10;
constexpr double kMaxAbsPositionM = 1e6;

void CheckRange(const Row& r, const std::string& path, const std::string& column, double value,
                double limit, const char* expected) {
  if (std::abs(value) <= limit) return;
  std::ostringstream m;
  m.precision(15);
  m << path << ":" << r.line << ": column '" << column << "': " << value << " is beyond +-" << limit
    << " (" << expected << ")";
  throw ReadError(m.str());
}

// Every value within its plausible range: time, then `limits[i]` for column `names[i]`.
void CheckRanges(const std::vector<Row>& rows, const std::string& path,
                 const std::vector<std::string>& names, const std::vector<double>& limits,
                 const std::vector<const char*>& expected) {
  for (const Row& r : rows) {
    CheckRange(r, path, "t", r.t, kMaxAbsTimeS,
               "seconds; a time in milliseconds or nanoseconds is this large");
    for (size_t i = 0; i < names.size() && i < r.v.size(); ++i)
      CheckRange(r, path, names[i], r.v[i], limits[i], expected[i]);
  }
}

void CheckOrder(const std::vector<Row>& rows, const std::string& path, const char* what) {
  if (rows.empty()) throw ReadError(path + ": no " + std::string(what) + " rows");
  for (size_t i = 1; i < rows.size(); ++i) {
    if (rows[i].t < rows[i - 1].t) {
      std::ostringstream m;
      m.precision(15);
      m << path << ":" << rows[i].line << ": time " << rows[i].t
        << " goes backwards (previous row, line " << rows[i - 1].line << ", has " << rows[i - 1].t
        << "); " << what << " rows must be in time order";
      throw ReadError(m.str());
    }
  }
}

Recording Assemble(std::string source, const std::vector<Row>& controls,
                   const std::vector<Row>& poses, int num_controls, const std::string& cpath,
                   const std::string& ppath) {
  CheckOrder(controls, cpath, "control");
  CheckOrder(poses, ppath, "pose");
  Recording rec;
  rec.source = std::move(source);
  rec.origin_s = std::min(controls.front().t, poses.front().t);
  // Spans must overlap.
  const double c0 = controls.front().t, c1 = controls.back().t;
  const double p0 = poses.front().t, p1 = poses.back().t;
  if (c1 < p0 || p1 < c0) {
    std::ostringstream m;
    m.precision(15);
    m << cpath << " and " << ppath << ": time spans do not overlap (controls " << c0 << ".." << c1
      << " s, poses " << p0 << ".." << p1 << " s): both files must share one time base";
    throw ReadError(m.str());
  }
  auto to_ns = [&](double t) { return SecondsToNs(t - rec.origin_s); };
  rec.controls = ControlSignal(num_controls, 0);
  ConflictingRepeats control_conflicts(cpath, "line"), pose_conflicts(ppath, "line");
  for (const auto& r : controls) {
    const size_t before = rec.controls.size();
    const TimeNs t_ns = to_ns(r.t);
    rec.controls.Append(t_ns, r.v);
    if (rec.controls.size() == before) ++rec.stats.control_repeated_times;
    control_conflicts.Add(t_ns, r.v, r.line);
  }
  rec.stats.control_rows = static_cast<int>(controls.size());
  rec.stats.pose_rows = static_cast<int>(poses.size());
  double max_abs_theta = 0.0;
  for (const auto& r : poses) max_abs_theta = std::max(max_abs_theta, std::abs(r.v[2]));
  if (max_abs_theta > 2.0 * M_PI + 0.5) {
    std::ostringstream m;
    m << ppath << ": theta reaches " << max_abs_theta
      << "; kincal expects radians (an unwrapped heading is fine, degrees are not)";
    rec.warnings.push_back(m.str());
  }
  for (const auto& r : poses) {
    RecordedPose s{to_ns(r.t), Eigen::Vector3d(r.v[0], r.v[1], WrapAngle(r.v[2]))};
    if (!rec.poses.empty() && rec.poses.back().t_ns == s.t_ns) {
      rec.poses.back() = s;
      ++rec.stats.pose_repeated_times;
    } else {
      rec.poses.push_back(s);
    }
    pose_conflicts.Add(s.t_ns, r.v, r.line);
  }
  for (const auto* c : {&control_conflicts, &pose_conflicts})
    if (c->count() > 0) rec.warnings.push_back(c->Warning());
  return rec;
}

// The rows of each run (by the 'run' column, in the order the controls first name them),
// each assembled on its own and the runs joined (JoinRuns: never across a run's start).
Recording AssembleRuns(const std::vector<Row>& controls, const std::vector<Row>& poses,
                       int num_controls, const std::string& cpath, const std::string& ppath) {
  std::vector<long long> order;
  std::map<long long, std::pair<std::vector<Row>, std::vector<Row>>> by_run;
  for (const Row& r : controls) {
    if (!by_run.count(r.run)) order.push_back(r.run);
    by_run[r.run].first.push_back(r);
  }
  for (const Row& r : poses) {
    if (!by_run.count(r.run)) {
      throw ReadError(ppath + ":" + std::to_string(r.line) + ": run " + std::to_string(r.run) +
                      " has poses but no controls in " + cpath);
    }
    by_run[r.run].second.push_back(r);
  }
  std::vector<Recording> parts;
  for (long long run : order) {
    const auto& [c, p] = by_run[run];
    if (p.empty()) {
      throw ReadError(cpath + ": run " + std::to_string(run) + " has controls but no poses in " +
                      ppath);
    }
    const std::string which = " (run " + std::to_string(run) + ")";
    parts.push_back(
        Assemble(cpath + " + " + ppath + which, c, p, num_controls, cpath + which, ppath + which));
  }
  StatusOr<Recording> rec = JoinRuns(std::move(parts));
  if (!rec.ok()) throw ReadError(rec.status().message());
  rec->source = cpath + " + " + ppath;
  return std::move(rec).value();
}

// A steering angle (a control in "rad") beyond a right angle is no car's: degrees.
void WarnOfSteeringInDegrees(const std::vector<Row>& controls, const KinematicModel& model,
                             const std::string& path, std::vector<std::string>* warnings) {
  for (size_t c = 0; c < model.controls().size(); ++c) {
    if (model.controls()[c].unit != "rad") continue;
    double most = 0.0;
    for (const auto& r : controls) most = std::max(most, std::abs(r.v[c]));
    if (most <= 0.5 * M_PI) continue;
    std::ostringstream m;
    m << path << ": column '" << model.controls()[c].name << "' reaches " << most
      << "; kincal expects a steering angle in radians (beyond a right angle, it looks like "
         "degrees)";
    warnings->push_back(m.str());
  }
}

Recording ReadCsvOrThrow(const std::string& controls_csv, const std::string& poses_csv,
                         const KinematicModel& model, bool positions, int max_lines) {
  std::vector<std::string> names;
  for (const auto& c : model.controls()) names.push_back(c.name);
  bool control_runs = false, pose_runs = false;
  const auto controls = ReadCsv(controls_csv, names, max_lines, &control_runs);
  LostPoses lost;
  const auto poses = ReadCsv(poses_csv, {"x", "y", "theta"}, max_lines, &pose_runs, &lost);
  if (poses.empty() && lost.rows() > 0)
    throw ReadError(poses_csv + ": no pose rows: every row's pose is empty or NaN");
  std::vector<double> limits;
  std::vector<const char*> expected;
  for (const auto& c : model.controls()) {
    limits.push_back(PlausibleControlLimit(c.unit));
    expected.push_back(c.unit.c_str());
  }
  CheckRanges(controls, controls_csv, positions ? std::vector<std::string>{} : names, limits,
              expected);  // positions: their times only
  CheckRanges(poses, poses_csv, {"x", "y", "theta"}, {kMaxAbsPositionM, kMaxAbsPositionM, 1e6},
              {"metres", "metres", "radians"});
  if (control_runs != pose_runs) {
    throw ReadError((control_runs ? controls_csv : poses_csv) + " has a 'run' column and " +
                    (control_runs ? poses_csv : controls_csv) +
                    " has none: number the runs in both files");
  }
  Recording rec = control_runs
                      ? AssembleRuns(controls, poses, model.num_controls(), controls_csv, poses_csv)
                      : Assemble(controls_csv + " + " + poses_csv, controls, poses,
                                 model.num_controls(), controls_csv, poses_csv);
  if (!positions) WarnOfSteeringInDegrees(controls, model, controls_csv, &rec.warnings);
  rec.stats.pose_rows_lost = lost.rows();
  if (lost.rows() > 0) rec.warnings.push_back(lost.Warning(poses_csv));
  return rec;
}

Recording ReadMrclamOrThrow(const std::string& dir, int robot, int max_lines) {
  if (robot < 1) throw ReadError("MR.CLAM robot number must be >= 1");
  const std::string base = dir + "/Robot" + std::to_string(robot);
  int comments = 0;
  const auto odo = ReadDat(base + "_Odometry.dat", 3, max_lines, &comments);
  const auto gt = ReadDat(base + "_Groundtruth.dat", 4, max_lines, &comments);
  CheckRanges(odo, base + "_Odometry.dat", {"v", "omega"},
              {PlausibleControlLimit("m/s"), PlausibleControlLimit("rad/s")}, {"m/s", "rad/s"});
  CheckRanges(gt, base + "_Groundtruth.dat", {"x", "y", "theta"},
              {kMaxAbsPositionM, kMaxAbsPositionM, 1e6}, {"metres", "metres", "radians"});
  Recording rec = Assemble("MR.CLAM " + dir + " robot " + std::to_string(robot), odo, gt, 2,
                           base + "_Odometry.dat", base + "_Groundtruth.dat");
  rec.stats.comment_lines = comments;
  return rec;
}

}  // namespace

bool RecordingLimits::IsValid(std::string* why) const {
  if (max_rows >= 1) return true;
  if (why) *why = "max_rows " + std::to_string(max_rows) + ": expected 1 or more";
  return false;
}

StatusOr<Recording> ReadCsvRecording(const std::string& controls_csv, const std::string& poses_csv,
                                     const KinematicModel& model, bool positions,
                                     const RecordingLimits& limits) {
  if (std::string why; !limits.IsValid(&why)) return Status::Error(why);
  return Catching(
      [&] { return ReadCsvOrThrow(controls_csv, poses_csv, model, positions, limits.max_rows); });
}

StatusOr<Recording> ReadMrclam(const std::string& dir, int robot, const RecordingLimits& limits) {
  if (std::string why; !limits.IsValid(&why)) return Status::Error(why);
  return Catching([&] { return ReadMrclamOrThrow(dir, robot, limits.max_rows); });
}

int RunOf(const Recording& rec, TimeNs t_ns) {
  const auto it = std::upper_bound(rec.runs.begin(), rec.runs.end(), t_ns,
                                   [](TimeNs t, const RecordingRun& r) { return t < r.start_ns; });
  return it == rec.runs.begin() ? 0 : static_cast<int>(it - rec.runs.begin()) - 1;
}

}  // namespace kincal
