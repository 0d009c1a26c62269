// kincald's command-line options over its configuration file: which source, how fast,
// what to record, where to checkpoint, which effects. One tested function, so that the
// executable only parses and prints.
#pragma once

#include <optional>
#include <string>

#include "kincal/daemon/config.h"
#include "kincal/status.h"

namespace kincal::daemon {

// What was given on the command line; empty / unset: the configuration's value stands.
struct CommandLineOptions {
  std::string device;              // --device: source v4l2 on this node
  std::string libcamera;           // --libcamera: source libcamera, this id or "first"
  std::string replay;              // --replay: source replay of this log
  std::optional<double> speed;     // --speed: replay or simulation speed factor
  bool fast = false;               // --fast: as fast as possible, lossless
  std::optional<double> duration;  // --duration: simulation length, s
  int loops = 1;                   // --loop: replay the log this many times
  std::string record;              // --record: LCM log of everything
  bool record_png = false;         // --record-png
  bool publish_frames = false;     // --publish-frames
  bool preview = false;            // --preview: preview.enabled
  std::string lcm_url;             // --lcm-url
  std::string resume;              // --resume: start from this checkpoint
  std::string checkpoint;          // --checkpoint: write checkpoints here
  bool resume_if_present = false;  // --resume-if-present: resume from --checkpoint if it exists
  std::string effects;             // --effects: "auto", "none" or a list (with "auto")
};

// Applies `o` to `config`; an error names the option and what it expects (and leaves
// `config` partly changed: use it only when the status is ok).
Status ApplyCommandLine(const CommandLineOptions& o, DaemonConfig* config);

}  // namespace kincal::daemon
