// Frames, control samples and poses as they move through kincald, and the frame-source
// interface that V4L2, libcamera, the simulated camera and log replay implement.
//
// Clocks (docs/daemon.md has the full table):
//   - `utime`: microseconds of the daemon host's realtime clock (LCM convention). The
//     pipeline's time base is `t_ns = utime * 1000`, so that a live run and a replay of its
//     log see the very same times.
//   - `*_mono_ns`: CLOCK_MONOTONIC of the daemon host (latency, pacing, timeouts).
//   - `device_*`: the source's own stamp (V4L2: kernel CLOCK_MONOTONIC of the buffer).
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "kincal/status.h"
#include "kincal/time.h"
#include "kincal/types.h"

namespace kincal::daemon {

// The pipeline's time base from a recorded realtime stamp, and back (exact both ways for
// the stamps the pipeline makes).
inline constexpr TimeNs UtimeToPipelineNs(int64_t utime) { return utime * 1000; }
inline constexpr int64_t PipelineNsToUtime(TimeNs t_ns) { return t_ns / 1000; }

// Packed 24-bit colour: kBgr24 stores bytes B, G, R (V4L2 BGR3, libcamera RGB888);
// kRgb24 stores R, G, B (V4L2 RGB3, libcamera BGR888).
enum class PixelFormat { kGrey, kYuyv, kMjpeg, kPng, kBgr24, kRgb24 };
std::string_view PixelFormatName(PixelFormat f);  // "GREY", "YUYV", "MJPG", "PNG", "BGR3", "RGB3"
// Throws std::invalid_argument naming the accepted formats.
PixelFormat ParsePixelFormat(std::string_view name);

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
// once it has the frame's size; MJPEG and PNG decoding allocate inside OpenCV). Throws
// FrameError naming the problem (short buffer, bad size, corrupt data).
class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
void ToGrey(const Frame& f, cv::Mat* grey);
// Raw GREY frame from a grey image (copies into f->data).
void FromGrey(const cv::Mat& grey, Frame* f);

struct ControlSample {
  int64_t utime = 0;          // the stamp the filter uses (receive or sender, see config)
  int64_t receive_utime = 0;  // host realtime clock at reception
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

enum class SourceStatus { kFrame, kTimeout, kEnd, kError };

// What a source can do, declared by the source itself; the daemon wires itself from this.
struct SourceCapabilities {
  bool lossless = false;                  // every frame must be processed (queues block): --fast
  bool carries_controls = false;          // the source hands the robot's controls over itself
  bool controls_end_with_frames = false;  // the robot is simulated or recorded: its controls
                                          // stop when the frames do
  bool can_reopen = false;                // a device that can be opened again after an error
};

// Something that supplies frames. Start() and Reopen() return a status naming the device,
// the step that failed and, for a failed system call, errno's text; Next() reports errors
// through `error`.

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::string name() const = 0;
  virtual Status Start() = 0;
  // Fills *f (reusing its buffer) or times out after timeout_ms.
  virtual SourceStatus Next(Frame* f, int timeout_ms, std::string* error) = 0;
  virtual void Stop() = 0;
  // After an error: close and open the device again; an error while it is still not
  // there. Sources that cannot reopen say so.
  virtual Status Reopen() { return Status::Error(name() + " cannot be reopened"); }
  // Frames the device itself lost (sequence gaps).
  virtual int64_t device_drops() const { return 0; }
  // Input the source could not use (undecodable log events).
  virtual int64_t rejected() const { return 0; }
  virtual SourceCapabilities capabilities() const = 0;
};

}  // namespace kincal::daemon
