// Time conventions.
//
// All times inside kincal are int64_t nanoseconds. Which clock a value is on is part of
// its name or comment:
//   - *_mono_ns : CLOCK_MONOTONIC of the daemon host (the daemon's internal clock)
//   - *_utime   : microseconds on the realtime epoch (LCM convention). In kincald these are
//                 pipeline stamps: CLOCK_MONOTONIC mapped onto the realtime epoch once
//                 per process (daemon/sources.h), so an NTP step does not move them;
//                 only health_t.utime is read from the host realtime clock itself
//   - *_dev_ns  : a device's own clock (camera, robot)
//   - t_ns      : a recording's time base (CSV files: seconds, converted once on read)
// Conversion happens once, at the edge where data enters or leaves.
#pragma once

#include <cmath>
#include <cstdint>

namespace kincal {

using TimeNs = int64_t;

inline constexpr TimeNs kNsPerSecond = 1'000'000'000;

inline constexpr double NsToSeconds(TimeNs ns) { return static_cast<double>(ns) * 1e-9; }
inline TimeNs SecondsToNs(double s) { return static_cast<TimeNs>(std::llround(s * 1e9)); }

}  // namespace kincal
