// Control samples and poses as they move through kincald, and the pipeline's time base.
//
// `utime` fields are microseconds on the pipeline clock (docs/daemon.md, "Clocks"); the
// filter's time base is `t_ns = utime * 1000`, so that a live run and a replay of its log
// see the very same times.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "kincal/time.h"
#include "kincal/types.h"

namespace kincal {

// The pipeline's time base from a recorded realtime stamp, and back (exact both ways for
// the stamps the pipeline makes).
inline constexpr TimeNs UtimeToPipelineNs(int64_t utime) { return utime * 1000; }
inline constexpr int64_t PipelineNsToUtime(TimeNs t_ns) { return t_ns / 1000; }

struct ControlSample {
  int64_t utime = 0;          // the stamp the filter uses (receive or sender, see config)
  int64_t receive_utime = 0;  // pipeline clock at reception
  int64_t sender_utime = 0;   // sender's stamp (0 if unknown)
  std::array<double, kMaxControls> values{};  // in the model's control order
};

inline constexpr int kMaxMarkers = 16;

struct PoseSample {
  int64_t utime = 0;  // of the frame (exposure start)
  int64_t device_utime = 0;
  int64_t sequence = 0;
  TimeNs arrival_mono_ns = 0;
  bool valid = false;
  Eigen::Vector3d xytheta = Eigen::Vector3d::Zero();  // floor frame (m, m, rad)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double rms_px = 0.0;
  int num_markers = 0;  // detected (identified or not)
  std::array<double, kMaxMarkers> u{}, v{};
  std::array<int, kMaxMarkers> id{};
};

}  // namespace kincal
