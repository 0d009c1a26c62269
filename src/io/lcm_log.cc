// Reads controls and poses from a kincald LCM event log.

#include <algorithm>
#include <cmath>
#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>
#include <kincal/run_t.hpp>
#include <memory>
#include <optional>

#include "kincal/angles.h"
#include "kincal/io/lcm_guard.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/io/recording.h"
#include "repeated_times.h"

namespace kincal {

namespace {

// What the decoders below throw on bad input; caught in ReadLcmLog, which returns it as a
// Status.
class ReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr const char* kRunChannel = "KINCAL_RUN";

struct TimedControls {
  double t;  // s, the message's utime
  std::vector<double> v;
  int64_t event = 0;  // its number in the log
};
struct TimedPose {
  double t;  // s, the message's utime
  Eigen::Vector3d z;
  int64_t event = 0;
};

// One controls_t event as the model's control vector; throws naming `where` and the fault.
TimedControls DecodeControls(const LcmLogEvent& ev, const std::string& where,
                             const KinematicModel& model) {
  kincal::controls_t m;
  std::string why;
  if (!PlausibleControls(ev.data.data(), ev.data.size(), kMaxControls, &why)) {
    throw ReadError(where + " on " + ev.channel + ": " + why);
  }
  if (m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) < 0) {
    throw ReadError(where + " on " + ev.channel + ": not a kincal.controls_t");
  }
  // Map the recorded channel names onto the model's control order.
  std::vector<double> v(static_cast<size_t>(model.num_controls()), 0.0);
  std::vector<bool> seen(v.size(), false);
  for (int i = 0; i < m.num_controls; ++i) {
    const std::string& name = m.names[static_cast<size_t>(i)];
    const double value = m.values[static_cast<size_t>(i)];
    const int k = model.ControlIndex(name);
    if (k < 0) {
      throw ReadError(where + ": control '" + name + "' is not a control of model '" +
                      std::string(model.name()) + "'");
    }
    if (!std::isfinite(value)) throw ReadError(where + ": control '" + name + "' is not finite");
    v[static_cast<size_t>(k)] = value;
    seen[static_cast<size_t>(k)] = true;
  }
  for (size_t k = 0; k < seen.size(); ++k) {
    if (!seen[k]) throw ReadError(where + ": control '" + model.controls()[k].name + "' missing");
  }
  return {static_cast<double>(m.utime) * 1e-6, std::move(v), ev.eventnum};
}

// One pose_t event; nothing for a pose marked invalid. Throws naming `where`.
std::optional<TimedPose> DecodePose(const LcmLogEvent& ev, const std::string& where) {
  kincal::pose_t m;
  if (m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) < 0) {
    throw ReadError(where + " on " + ev.channel + ": not a kincal.pose_t");
  }
  if (!m.valid) return std::nullopt;
  const Eigen::Vector3d z(m.x, m.y, m.theta);
  if (!z.allFinite()) throw ReadError(where + ": pose is not finite");
  return TimedPose{static_cast<double>(m.utime) * 1e-6, z, ev.eventnum};
}

// One run_t event: the run's start (s, its utime) and source. Throws naming `where`.
RecordingRun DecodeRun(const LcmLogEvent& ev, const std::string& where, double* start_s) {
  kincal::run_t m;
  if (m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) < 0) {
    throw ReadError(where + " on " + ev.channel + ": not a kincal.run_t");
  }
  *start_s = static_cast<double>(m.utime) * 1e-6;
  return {0, m.source};
}

// The runs' starts on the recording's time base; they must increase.
void PlaceRuns(const std::vector<std::pair<double, RecordingRun>>& runs, const std::string& path,
               Recording* rec) {
  for (const auto& [t, run] : runs) {
    RecordingRun r = run;
    r.start_ns = SecondsToNs(t - rec->origin_s);
    if (!rec->runs.empty() && r.start_ns <= rec->runs.back().start_ns) {
      throw ReadError(path + ": run " + std::to_string(rec->runs.size() + 1) +
                      " starts before run " + std::to_string(rec->runs.size()) +
                      " (runs must be in time order)");
    }
    rec->runs.push_back(r);
  }
  // Samples before the first marked run belong to it.
  if (!rec->runs.empty())
    rec->runs.front().start_ns = std::min<TimeNs>(rec->runs.front().start_ns, 0);
}

// The streams (in arrival order) as a recording: each sorted by its own stamps (stable),
// times from the earlier first sample, repeated stamps counted (and said when their values
// differ). `channels`: the controls' and the poses'.
Recording Assemble(std::vector<TimedControls> controls, std::vector<TimedPose> poses,
                   const KinematicModel& model, const std::string& path,
                   const std::pair<std::string, std::string>& channels) {
  std::stable_sort(controls.begin(), controls.end(),
                   [](const TimedControls& a, const TimedControls& b) { return a.t < b.t; });
  std::stable_sort(poses.begin(), poses.end(),
                   [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
  Recording rec;
  rec.source = path;
  rec.origin_s = std::min(controls.front().t, poses.front().t);
  rec.controls = ControlSignal(model.num_controls(), 0);
  RecordingStats stats;
  ConflictingRepeats control_conflicts(path + " " + channels.first, "event");
  ConflictingRepeats pose_conflicts(path + " " + channels.second, "event");
  for (const auto& c : controls) {
    const size_t before = rec.controls.size();
    const TimeNs t_ns = SecondsToNs(c.t - rec.origin_s);
    rec.controls.Append(t_ns, c.v);
    if (rec.controls.size() == before) ++stats.control_repeated_times;
    control_conflicts.Add(t_ns, c.v, c.event);
  }
  for (const TimedPose& p : poses) {
    const Eigen::Vector3d& z = p.z;
    RecordedPose s{SecondsToNs(p.t - rec.origin_s),
                   Eigen::Vector3d(z.x(), z.y(), WrapAngle(z.z()))};
    if (!rec.poses.empty() && rec.poses.back().t_ns == s.t_ns) {
      rec.poses.back() = s;
      ++stats.pose_repeated_times;
    } else {
      rec.poses.push_back(s);
    }
    pose_conflicts.Add(s.t_ns, std::span<const double>(z.data(), 3), p.event);
  }
  for (const auto* c : {&control_conflicts, &pose_conflicts})
    if (c->count() > 0) rec.warnings.push_back(c->Warning());
  stats.control_rows = static_cast<int>(controls.size());
  stats.pose_rows = static_cast<int>(poses.size());
  rec.stats = stats;
  return rec;
}

// Throws naming the log and `channel` when `samples` is past the bound.
void CheckBound(size_t samples, int max_rows, const std::string& path, const std::string& channel) {
  if (samples <= static_cast<size_t>(max_rows)) return;
  throw ReadError(path + ": more than " + std::to_string(max_rows) + " samples on " + channel +
                  ", the most read from one log (" + std::string(kMaxRowsAdvice) + ")");
}

Recording ReadLcmLogOrThrow(const std::string& path, const KinematicModel& model,
                            const std::string& controls_channel, const std::string& pose_channel,
                            int max_rows) {
  std::unique_ptr<LcmLogReader> log;
  if (const Status s = LcmLogReader::Open(path, &log); !s.ok()) throw ReadError(s.message());
  std::vector<TimedControls> controls;
  std::vector<TimedPose> poses;
  std::vector<std::pair<double, RecordingRun>> runs;
  LcmLogEvent ev;
  while (log->Next(&ev)) {
    const std::string where = path + ": event " + std::to_string(ev.eventnum) + " (byte " +
                              std::to_string(ev.offset) + ")";
    if (ev.channel == controls_channel) {
      controls.push_back(DecodeControls(ev, where, model));
      CheckBound(controls.size(), max_rows, path, controls_channel);
    } else if (ev.channel == pose_channel) {
      if (auto p = DecodePose(ev, where)) poses.push_back(*p);
      CheckBound(poses.size(), max_rows, path, pose_channel);
    } else if (ev.channel == kRunChannel) {
      double t = 0;
      RecordingRun r = DecodeRun(ev, where, &t);
      runs.emplace_back(t, std::move(r));
      CheckBound(runs.size(), max_rows, path, kRunChannel);
    }
  }
  if (controls.empty()) throw ReadError(path + ": no controls on channel " + controls_channel);
  if (poses.empty()) throw ReadError(path + ": no poses on channel " + pose_channel);
  Recording rec = Assemble(std::move(controls), std::move(poses), model, path,
                           {controls_channel, pose_channel});
  PlaceRuns(runs, path, &rec);
  // Damage is not fatal (the rest of the log is still good) but never silent.
  for (const auto& p : log->problems()) rec.warnings.push_back(p);
  if (log->damaged_stretches() > static_cast<int64_t>(log->problems().size())) {
    rec.warnings.push_back(path + ": " + std::to_string(log->damaged_stretches()) +
                           " damaged stretches in all, " + std::to_string(log->damaged_bytes()) +
                           " bytes skipped");
  }
  return rec;
}

}  // namespace

StatusOr<Recording> ReadLcmLog(const std::string& path, const KinematicModel& model,
                               const RecordingLimits& limits, const std::string& controls_channel,
                               const std::string& pose_channel) {
  if (std::string why; !limits.IsValid(&why)) return Status::Error(why);
  try {
    return ReadLcmLogOrThrow(path, model, controls_channel, pose_channel, limits.max_rows);
  } catch (const ReadError& e) {
    return Status::Error(e.what());
  }
}

}  // namespace kincal
