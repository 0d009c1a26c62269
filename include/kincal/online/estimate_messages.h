// The online estimator's results as kincal's LCM types (params_t, calibration_t,
// model_check_t): its outputs are the messages kincald publishes, so that a test or a tool
// reads them without LCM (the types are headers; nothing here links LCM). Each builder
// fills a message the caller keeps and reuses (vectors keep their capacity).
#pragma once

#include <kincal/calibration_t.hpp>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "kincal/analysis/model_check.h"
#include "kincal/online/batch_calibration.h"
#include "kincal/online/samples.h"
#include "kincal/system.h"

namespace kincal {

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

}  // namespace kincal
