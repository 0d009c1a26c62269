// Recordings of one robot joined as the runs of one recording (recording.h).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "kincal/io/recording.h"

namespace kincal {
namespace {

// The last sample's time (ns, the part's own base).
TimeNs EndOf(const Recording& r) {
  TimeNs end = r.poses.empty() ? 0 : r.poses.back().t_ns;
  if (!r.controls.empty())
    end =
        std::max(end, r.controls.ToNs(r.controls.TimeAt(static_cast<int>(r.controls.size()) - 1)));
  return end;
}

// Appends `part`, its times moved by `shift_ns` onto `out`'s base.
void AppendPart(const Recording& part, TimeNs shift_ns, Recording* out) {
  const size_t first_run = out->runs.size();
  if (part.runs.empty()) {
    out->runs.push_back({shift_ns, part.source});
  } else {
    for (const auto& r : part.runs)
      out->runs.push_back({r.start_ns + shift_ns, r.source.empty() ? part.source : r.source});
  }
  // The run starts no later than its first sample.
  TimeNs first = part.poses.empty() ? 0 : part.poses.front().t_ns;
  if (!part.controls.empty()) first = std::min(first, part.controls.ToNs(part.controls.TimeAt(0)));
  out->runs[first_run].start_ns = std::min(out->runs[first_run].start_ns, first + shift_ns);
  for (size_t i = 0; i < part.controls.size(); ++i) {
    const int k = static_cast<int>(i);
    const auto& v = part.controls.ValuesAt(k);
    out->controls.Append(
        part.controls.ToNs(part.controls.TimeAt(k)) + shift_ns,
        std::span<const double>(v.data(), static_cast<size_t>(part.controls.num_channels())));
  }
  for (const auto& p : part.poses) out->poses.push_back({p.t_ns + shift_ns, p.z});
  const RecordingStats& s = part.stats;
  out->stats.control_rows += s.control_rows;
  out->stats.pose_rows += s.pose_rows;
  out->stats.pose_rows_lost += s.pose_rows_lost;
  out->stats.control_repeated_times += s.control_repeated_times;
  out->stats.pose_repeated_times += s.pose_repeated_times;
  out->stats.comment_lines += s.comment_lines;
  for (const auto& w : part.warnings) out->warnings.push_back(w);
}

}  // namespace

StatusOr<Recording> JoinRuns(std::vector<Recording> parts) {
  if (parts.size() == 1) return std::move(parts.front());
  Recording out;
  if (parts.empty()) return out;
  out.origin_s = parts.front().origin_s;
  out.controls = ControlSignal(parts.front().controls.num_channels(), 0);
  TimeNs previous_end = 0;
  for (size_t k = 0; k < parts.size(); ++k) {
    const Recording& part = parts[k];
    if (part.controls.num_channels() != out.controls.num_channels()) {
      return Status::Error(part.source + ": " + std::to_string(part.controls.num_channels()) +
                           " control channels, the first recording has " +
                           std::to_string(out.controls.num_channels()));
    }
    out.source += (k == 0 ? "" : " + ") + part.source;
    // The part's own times on the joined base (each part's t = 0 is its origin_s).
    TimeNs shift = SecondsToNs(part.origin_s - out.origin_s);
    const TimeNs earliest = previous_end + SecondsToNs(kRunGapS);
    if (k > 0 && shift < earliest) {
      std::ostringstream m;
      m << part.source << ": starts " << NsToSeconds(earliest - shift)
        << " s too early to follow the previous run (each file on its own clock, or out of "
           "order): moved to start "
        << kRunGapS << " s after it";
      out.warnings.push_back(m.str());
      shift = earliest;
    }
    AppendPart(part, shift, &out);
    previous_end = EndOf(part) + shift;
  }
  return out;
}

}  // namespace kincal
