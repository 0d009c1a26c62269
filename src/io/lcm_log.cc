// Reads controls and poses from a kincald LCM event log.
#include <sys/stat.h>

#include <cmath>
#include <kincal/controls_t.hpp>
#include <kincal/pose_t.hpp>
#include <optional>

#include "kincal/angles.h"
#include "kincal/io/lcm_guard.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/io/recording.h"

namespace kincal {

Recording ReadLcmLog(const std::string& path, const KinematicModel& model,
                     const std::string& controls_channel, const std::string& pose_channel) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw RecordingError(path + ": cannot open for reading");
  std::optional<LcmLogReader> log;
  try {
    log.emplace(path);
  } catch (const std::runtime_error& e) {
    throw RecordingError(e.what());
  }
  // Map the recorded channel names onto the model's control order.
  std::vector<int> order;
  struct C {
    double t;
    std::vector<double> v;
  };
  std::vector<C> controls;
  std::vector<std::pair<double, Eigen::Vector3d>> poses;
  RecordingStats stats;
  LcmLogEvent e;
  const LcmLogEvent* ev = &e;
  while (log->Next(&e)) {
    const std::string where = path + ": event " + std::to_string(ev->eventnum) + " (byte " +
                              std::to_string(ev->offset) + ")";
    if (ev->channel == controls_channel) {
      kincal::controls_t m;
      std::string why;
      if (!PlausibleControls(ev->data.data(), ev->data.size(), kMaxControls, &why)) {
        throw RecordingError(where + " on " + ev->channel + ": " + why);
      }
      if (m.decode(ev->data.data(), 0, static_cast<int>(ev->data.size())) < 0) {
        throw RecordingError(where + " on " + ev->channel + ": not a kincal.controls_t");
      }
      std::vector<double> v(static_cast<size_t>(model.num_controls()), 0.0);
      std::vector<bool> seen(v.size(), false);
      for (int i = 0; i < m.num_controls; ++i) {
        const int k = model.ControlIndex(m.names[static_cast<size_t>(i)]);
        if (k < 0) {
          throw RecordingError(where + ": control '" + m.names[static_cast<size_t>(i)] +
                               "' is not a control of model '" + std::string(model.name()) + "'");
        }
        if (!std::isfinite(m.values[static_cast<size_t>(i)])) {
          throw RecordingError(where + ": control '" + m.names[static_cast<size_t>(i)] +
                               "' is not finite");
        }
        v[static_cast<size_t>(k)] = m.values[static_cast<size_t>(i)];
        seen[static_cast<size_t>(k)] = true;
      }
      for (size_t k = 0; k < seen.size(); ++k) {
        if (!seen[k]) {
          throw RecordingError(where + ": control '" + model.controls()[k].name + "' missing");
        }
      }
      controls.push_back({static_cast<double>(m.utime) * 1e-6, std::move(v)});
    } else if (ev->channel == pose_channel) {
      kincal::pose_t m;
      if (m.decode(ev->data.data(), 0, static_cast<int>(ev->data.size())) < 0) {
        throw RecordingError(where + " on " + ev->channel + ": not a kincal.pose_t");
      }
      if (!m.valid) continue;
      const Eigen::Vector3d z(m.x, m.y, m.theta);
      if (!z.allFinite()) throw RecordingError(where + ": pose is not finite");
      poses.emplace_back(static_cast<double>(m.utime) * 1e-6, z);
    }
  }
  if (controls.empty()) throw RecordingError(path + ": no controls on channel " + controls_channel);
  if (poses.empty()) throw RecordingError(path + ": no poses on channel " + pose_channel);
  // Logs are written in arrival order; sort each stream by its own stamps (stable).
  std::stable_sort(controls.begin(), controls.end(),
                   [](const C& a, const C& b) { return a.t < b.t; });
  std::stable_sort(poses.begin(), poses.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  Recording rec;
  rec.source = path;
  rec.origin_s = std::min(controls.front().t, poses.front().first);
  rec.controls = ControlSignal(model.num_controls(), 0);
  for (const auto& c : controls) {
    const size_t before = rec.controls.size();
    rec.controls.Append(SecondsToNs(c.t - rec.origin_s), c.v);
    if (rec.controls.size() == before) ++stats.control_repeated_times;
  }
  for (const auto& [t, z] : poses) {
    RecordedPose s{SecondsToNs(t - rec.origin_s), Eigen::Vector3d(z.x(), z.y(), WrapAngle(z.z()))};
    if (!rec.poses.empty() && rec.poses.back().t_ns == s.t_ns) {
      rec.poses.back() = s;
      ++stats.pose_repeated_times;
    } else {
      rec.poses.push_back(s);
    }
  }
  stats.control_rows = static_cast<int>(controls.size());
  stats.pose_rows = static_cast<int>(poses.size());
  rec.stats = stats;
  // Damage is not fatal (the rest of the log is still good) but never silent.
  for (const auto& p : log->problems()) rec.warnings.push_back(p);
  if (log->damaged_stretches() > static_cast<int64_t>(log->problems().size())) {
    rec.warnings.push_back(path + ": " + std::to_string(log->damaged_stretches()) +
                           " damaged stretches in all, " + std::to_string(log->damaged_bytes()) +
                           " bytes skipped");
  }
  return rec;
}

}  // namespace kincal
