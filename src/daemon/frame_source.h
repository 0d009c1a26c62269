// The frame-source interface that V4L2, libcamera, the simulated camera and log replay
// implement.
#pragma once

#include <cstdint>
#include <string>

#include "kincal/daemon/frame.h"
#include "kincal/status.h"

namespace kincal::daemon {

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
