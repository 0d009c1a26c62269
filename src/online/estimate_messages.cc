#include "kincal/online/estimate_messages.h"

#include <algorithm>
#include <cmath>

namespace kincal {

void FillParamsMessage(const System& sys, const StateVec& state, const StateMat& covariance,
                       std::string_view estimator, int64_t update_count, int64_t utime,
                       kincal::params_t* m) {
  const size_t n = static_cast<size_t>(sys.num_params());
  m->schema_version = 3;
  m->utime = utime;
  m->model = std::string(sys.model().name());
  m->estimator = std::string(estimator);
  m->num_params = static_cast<int32_t>(n);
  m->names.resize(n);
  m->units.resize(n);
  m->values.resize(n);
  m->sigmas.resize(n);
  m->covariance.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const int a = static_cast<int>(i);
    m->names[i] = sys.params()[i].name;
    m->units[i] = sys.params()[i].unit;
    m->values[i] = state[a];
    m->sigmas[i] = std::sqrt(std::max(0.0, covariance(a, a)));
    m->covariance[i].resize(n);
    for (size_t k = 0; k < n; ++k) m->covariance[i][k] = covariance(a, static_cast<int>(k));
  }
  m->update_count = update_count;
  m->source = kincal::params_t::SOURCE_FILTER;
}

namespace {

// names, units, values, sigmas and the covariance of a batch calibration into the vectors
// of a params_t or a calibration_t (the two lay them out alike).
template <typename Message>
void FillParameterBlock(const BatchCalibration& c, Message* m) {
  const size_t n = c.params.size();
  m->num_params = static_cast<int32_t>(n);
  m->names.resize(n);
  m->units.resize(n);
  m->values.resize(n);
  m->sigmas.resize(n);
  m->covariance.resize(n);
  for (size_t i = 0; i < n; ++i) {
    m->names[i] = c.params[i].name;
    m->units[i] = c.params[i].unit;
    m->values[i] = c.params[i].value;
    m->sigmas[i] = c.params[i].sigma;
    m->covariance[i].resize(n);
    for (size_t k = 0; k < n; ++k) {
      m->covariance[i][k] = c.covariance(static_cast<int>(i), static_cast<int>(k));
    }
  }
}

}  // namespace

void FillParamsFromCalibration(const BatchCalibration& c, const std::string& model,
                               int64_t update_count, int64_t utime, kincal::params_t* m) {
  m->schema_version = 3;
  m->utime = utime;
  m->model = model;
  m->estimator = "batch";
  FillParameterBlock(c, m);
  m->update_count = update_count;
  m->source = kincal::params_t::SOURCE_BATCH;
}

void FillCalibrationMessage(const BatchCalibration& run, const BatchCalibration* good,
                            const std::string& model, int64_t poses_thinned,
                            kincal::calibration_t* m) {
  m->schema_version = 1;
  m->utime = PipelineNsToUtime(run.data_end_ns);
  m->sequence = run.sequence;
  m->ok = run.ok ? 1 : 0;
  m->error = run.error;
  m->data_begin_utime = PipelineNsToUtime(run.data_begin_ns);
  m->data_end_utime = PipelineNsToUtime(run.data_end_ns);
  m->num_poses = run.num_poses;
  m->num_controls = run.num_controls;
  m->poses_thinned = poses_thinned;
  m->compute_s = run.compute_s;
  const BatchCalibration none;
  const BatchCalibration& c = good != nullptr ? *good : none;
  m->calibration_sequence = good != nullptr ? good->sequence : 0;
  m->model = ModelLabel(model, c.effects);
  m->num_effects = static_cast<int32_t>(c.effects.size());
  m->effects = c.effects;
  FillParameterBlock(c, m);
  m->num_accepted = static_cast<int32_t>(c.accepted.size());
  m->accepted = c.accepted;
  m->accepted_evidence = c.accepted_evidence;
  m->accepted_evidence.resize(c.accepted.size());
  m->horizon_s = c.horizon_s;
  m->heldout_before_m = c.heldout_before_m;
  m->heldout_after_m = c.heldout_after_m;
  m->heldout_before_rad = c.heldout_before_rad;
  m->heldout_after_rad = c.heldout_after_rad;
  m->unique = c.unique ? 1 : 0;
  m->warnings = c.warnings;
  m->prior = c.prior;
}

kincal::model_check_t ModelCheckMessage(const ModelCheckVerdict& v, const std::string& model,
                                        int64_t utime) {
  kincal::model_check_t m{};
  m.schema_version = 2;
  m.utime = utime;
  m.model = model;
  m.consistent = v.consistent ? 1 : 0;
  m.nis_mean = v.nis_mean;
  m.nis_expected = v.nis_expected;
  m.window = v.window;
  m.window_capacity = v.window_capacity;
  m.suspected_effect = v.suspected_effect;
  m.num_candidates = static_cast<int32_t>(v.candidates.size());
  m.candidates = v.candidates;
  m.confidence = v.confidence;
  m.evidence = v.evidence;
  m.num_added = 0;
  return m;
}

std::string ModelLabel(std::string_view model, const std::vector<std::string>& effects) {
  std::string label(model);
  for (const auto& e : effects) label += "+" + e;
  return label;
}

}  // namespace kincal
