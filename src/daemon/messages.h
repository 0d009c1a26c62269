// Every LCM message kincald publishes, built from the pipeline's own types. Each builder
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

#include "daemon/batch_worker.h"
#include "daemon/samples.h"
#include "kincal/analysis/model_check.h"
#include "kincal/daemon/config.h"
#include "kincal/daemon/daemon.h"
#include "kincal/daemon/frame.h"
#include "kincal/estimation/filter.h"
#include "kincal/plan/advice.h"
#include "kincal/system.h"

namespace kincal::daemon {

// A frame as recorded: raw, or a GREY frame compressed to PNG (`png`: scratch buffer).
// Throws FrameError when the frame cannot be turned into grey for PNG.
void FillFrameMessage(const Frame& f, FrameEncoding encoding, std::vector<uint8_t>* png,
                      kincal::frame_t* m);
void FillPoseMessage(const PoseSample& p, kincal::pose_t* m);
void FillMarkersMessage(const PoseSample& p, double sigma_px, kincal::markers_t* m);
// The parameter block of a state: values, sigmas and covariance, by name and unit. The
// status (params_t::STATUS_*) is the caller's to set.
void FillParamsMessage(const System& sys, const StateVec& state, const StateMat& covariance,
                       std::string_view estimator, int64_t update_count, int64_t utime,
                       kincal::params_t* m);
// A batch's message: what this batch did (`run`: sequence, success or why not, its data,
// its time), and the calibration in force (`good`: the last good batch, null when none;
// model, effects, parameters, the effects accepted and the held-out errors).
void FillCalibrationMessage(const BatchCalibration& run, const BatchCalibration* good,
                            const std::string& model, int64_t poses_thinned,
                            kincal::calibration_t* m);
// A batch calibration as a params_t (source SOURCE_BATCH, estimator "batch"); the status
// is the caller's to set.
void FillParamsFromCalibration(const BatchCalibration& c, const std::string& model,
                               int64_t update_count, int64_t utime, kincal::params_t* m);
kincal::model_check_t ModelCheckMessage(const ModelCheckVerdict& v, const std::string& model,
                                        int64_t utime);
// "model+effect+effect", as model_check_t and guidance_t name the system in use.
std::string ModelLabel(std::string_view model, const std::vector<std::string>& effects);
// What to drive next (kincal/plan/advice.h) on the estimate's system.
void FillGuidanceMessage(const System& sys, const std::string& model, const Advice& advice,
                         const PlanOptions& o, int64_t utime, kincal::guidance_t* m);
// The counters, whole, into a health message (the status fields are the caller's).
void FillHealthCounters(const DaemonCounters& c, kincal::health_t* m);

}  // namespace kincal::daemon
