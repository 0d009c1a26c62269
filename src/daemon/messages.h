// Every LCM message kincald publishes, built from the pipeline's own types (the
// estimate's: kincal/online/estimate_messages.h). Each builder
// fills a message the caller keeps and reuses (vectors keep their capacity).
#pragma once

#include <kincal/calibration_t.hpp>
#include <kincal/frame_t.hpp>
#include <kincal/guidance_t.hpp>
#include <kincal/health_t.hpp>
#include <kincal/markers_t.hpp>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/daemon/config.h"
#include "kincal/daemon/daemon.h"
#include "kincal/daemon/frame.h"
#include "kincal/estimation/filter.h"
#include "kincal/online/estimate_messages.h"
#include "kincal/online/samples.h"
#include "kincal/plan/advice.h"
#include "kincal/system.h"

namespace kincal::daemon {

// A frame as recorded: raw, or a GREY frame compressed to PNG (`png`: scratch buffer).
// A frame that cannot be turned into grey for PNG or JPEG is filled raw, as it came (the
// recording keeps it), and the error says why.
Status FillFrameMessage(const Frame& f, FrameEncoding encoding, std::vector<uint8_t>* png,
                        kincal::frame_t* m);
void FillPoseMessage(const PoseSample& p, kincal::pose_t* m);
void FillMarkersMessage(const PoseSample& p, double sigma_px, kincal::markers_t* m);
// What to drive next (kincal/plan/advice.h) on the estimate's system.
void FillGuidanceMessage(const System& sys, const std::string& model, const Advice& advice,
                         const PlanOptions& o, int64_t utime, kincal::guidance_t* m);
// The counters, whole, into a health message (the status fields are the caller's).
void FillHealthCounters(const DaemonCounters& c, kincal::health_t* m);

}  // namespace kincal::daemon
