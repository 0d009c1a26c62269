// Camera frames as they move through kincald: pixel formats, the frame buffer, and
// decoding any of them to grey. (Poses and controls: kincal/online/samples.h; the source interface:
// src/daemon/frame_source.h.)
//
// Clocks (docs/daemon.md has the full table):
//   - `utime`: microseconds on the pipeline clock (LCM convention; kincal/online/samples.h).
//   - `*_mono_ns`: CLOCK_MONOTONIC of the daemon host (latency, pacing, timeouts).
//   - `device_*`: the source's own stamp (V4L2: kernel CLOCK_MONOTONIC of the buffer).
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "kincal/status.h"
#include "kincal/time.h"
#include "kincal/types.h"

namespace kincal::daemon {

// Packed 24-bit colour: kBgr24 stores bytes B, G, R (V4L2 BGR3, libcamera RGB888);
// kRgb24 stores R, G, B (V4L2 RGB3, libcamera BGR888).
enum class PixelFormat { kGrey, kYuyv, kMjpeg, kPng, kBgr24, kRgb24 };
std::string_view PixelFormatName(PixelFormat f);  // "GREY", "YUYV", "MJPG", "PNG", "BGR3", "RGB3"
// An error names the accepted formats.
StatusOr<PixelFormat> ParsePixelFormat(std::string_view name);

struct Frame {
  std::vector<uint8_t> data;              // capacity is kept when a Frame is reused
  int width = 0, height = 0, stride = 0;  // stride: bytes per row (raw formats)
  PixelFormat format = PixelFormat::kGrey;
  int64_t utime = 0;                 // exposure start, us, host realtime clock
  int64_t device_utime = 0;          // source's own stamp, us (0 if none)
  int64_t sequence = 0;              // source sequence number (gaps: dropped frames)
  TimeNs arrival_mono_ns = 0;        // when the source handed the frame over (latency start)
  bool tstamp_end_of_frame = false;  // V4L2: the device stamped the end, not the start
};

// Decodes any supported format into an 8-bit grey image. `grey` is reused (no allocation
// once it has the frame's size; MJPEG and PNG decoding allocate inside OpenCV). An error
// names the problem (short buffer, bad size, corrupt data).
Status ToGrey(const Frame& f, cv::Mat* grey);
// Raw GREY frame from a grey image (copies into f->data).
void FromGrey(const cv::Mat& grey, Frame* f);

}  // namespace kincal::daemon
