#include "kincal/daemon/command_line.h"

#include <filesystem>
#include <vector>

#include "kincal/analysis/option_lists.h"

namespace kincal::daemon {
namespace {

void ApplySource(const CommandLineOptions& o, DaemonConfig* c) {
  if (!o.device.empty()) {
    c->source = SourceKind::kV4l2;
    c->v4l2.device = o.device;
  } else if (!o.libcamera.empty()) {
    c->source = SourceKind::kLibcamera;
    c->libcamera.camera = o.libcamera == "first" ? "" : o.libcamera;
  } else if (!o.replay.empty()) {
    c->source = SourceKind::kReplay;
    c->replay.path = o.replay;
  }
  // --fast and --speed reach the source that paces: replay or simulation.
  double* speed = c->source == SourceKind::kReplay ? &c->replay.speed
                  : c->source == SourceKind::kSim  ? &c->sim.speed
                                                   : nullptr;
  if (speed != nullptr) *speed = o.fast ? 0.0 : o.speed.value_or(*speed);
}

Status ApplyEffects(const std::string& text, RobotOptions* robot) {
  std::vector<std::string> list;
  if (Status s = ParseEffectList(text == "none" ? "" : text, &list); !s.ok()) return s;
  robot->effects.clear();
  robot->auto_effects = false;
  for (const std::string& e : list) {
    if (e == "auto") {
      robot->auto_effects = true;
    } else {
      robot->effects.push_back(e);
    }
  }
  return {};
}

// What kincald writes and publishes, and the checkpoint it starts from.
void ApplyOutputs(const CommandLineOptions& o, DaemonConfig* c) {
  if (!o.record.empty()) c->record.path = o.record;
  if (o.record_png) c->record.frame_encoding = FrameEncoding::kPng;
  if (o.publish_frames) c->lcm.publish_frames = true;
  if (o.preview) c->preview.enabled = true;
  if (!o.lcm_url.empty()) c->lcm.url = o.lcm_url;
  if (!o.resume.empty()) c->checkpoint.resume = o.resume;
  if (!o.checkpoint.empty()) c->checkpoint.path = o.checkpoint;
  std::error_code ec;
  if (o.resume_if_present && !c->checkpoint.path.empty() &&
      std::filesystem::exists(c->checkpoint.path, ec)) {
    c->checkpoint.resume = c->checkpoint.path;
  }
}

}  // namespace

Status ApplyCommandLine(const CommandLineOptions& o, DaemonConfig* c) {
  if (o.fast && o.speed) return Status::Error("--speed and --fast exclude each other");
  if (o.loops < 1) return Status::Error("--loop: expected a count >= 1");
  const int sources = !o.device.empty() + !o.libcamera.empty() + !o.replay.empty();
  if (sources > 1) return Status::Error("--device, --libcamera and --replay exclude each other");
  ApplySource(o, c);
  if (o.duration) {
    if (!(*o.duration > 0 && *o.duration <= kMaxSimDurationS)) {
      return Status::Error("--duration: expected seconds > 0 and at most " +
                           std::to_string(static_cast<int64_t>(kMaxSimDurationS)) + " (30 days)");
    }
    c->sim.duration_s = *o.duration;
  }
  if (!o.effects.empty()) {
    if (Status s = ApplyEffects(o.effects, &c->robot); !s.ok()) return s;
  }
  if (o.loops > 1) c->replay.loops = o.loops;
  ApplyOutputs(o, c);
  return {};
}

}  // namespace kincal::daemon
