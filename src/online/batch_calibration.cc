#include "kincal/online/batch_calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace kincal {
namespace {

// Thrown from Analyze's progress callback when the batch is cancelled; caught in
// RunBatchCalibration below, never outside this file.
class Cancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string TrialEvidence(const EffectTrial& t) {
  std::ostringstream ev;
  ev.precision(3);
  ev << t.name << (t.accepted ? " accepted" : " rejected") << " (held-out gain " << t.heldout_gain
     << ", dBIC " << t.delta_bic;
  for (const auto& p : t.params) ev << ", " << p.name << " " << p.value << " +- " << p.sigma;
  ev << ")";
  return ev.str();
}

}  // namespace

BatchCalibration CalibrationFrom(const AnalyzeResult& a, const std::vector<std::string>& declared) {
  BatchCalibration c;
  c.effects = a.after.effects;
  for (size_t i = declared.size(); i < a.after.effects.size(); ++i) {
    c.accepted.push_back(a.after.effects[i]);
  }
  std::string all;
  for (const auto& t : a.trials) {
    const std::string line = TrialEvidence(t);
    all += (all.empty() ? "" : "; ") + line;
    if (t.accepted) c.accepted_evidence.push_back(line);
  }
  c.evidence = all;
  c.params = a.after.params;
  c.covariance = a.after.covariance;
  c.horizon_s = a.horizon_s;
  c.heldout_before_m = a.before.heldout.pos_rms_m;
  c.heldout_after_m = a.after.heldout.pos_rms_m;
  c.heldout_before_rad = a.before.heldout.heading_rms_rad;
  c.heldout_after_rad = a.after.heldout.heading_rms_rad;
  c.unique = a.after.unique;
  for (const auto& w : a.warnings) c.warnings += w + "\n";
  const auto n = static_cast<Eigen::Index>(c.params.size());
  bool finite = c.covariance.rows() == n && c.covariance.cols() == n && c.covariance.allFinite();
  for (const auto& p : c.params)  // a held parameter (robot.fixed) has sigma 0 by design
    finite = finite && std::isfinite(p.value) && (p.sigma > 0 || p.held);
  // A fit analyze calls not unique (several optima, or a model that predicts no better
  // than a guess ignoring the commands) is still what the data say, as `kincal analyze`
  // reports it: published, flagged (unique = false, the reason in the warnings), and the
  // filter does not follow it (filter_stage.cc).
  if (!a.after.unique) c.warnings += "not unique: " + a.after.uniqueness + "\n";
  if (!finite) {
    c.error = "the fit gave no usable covariance";
  } else {
    c.ok = true;
  }
  return c;
}

BatchCalibration RunBatchCalibration(int sequence, const Recording& data,
                                     const AnalyzeOptions& options,
                                     const std::function<const char*()>& cancelled) {
  AnalyzeOptions o = options;
  if (cancelled) {
    o.progress = [&cancelled](double, const std::string&) {
      if (const char* why = cancelled()) throw Cancelled(why);
    };
  }
  const auto start = std::chrono::steady_clock::now();
  BatchCalibration r;
  try {
    StatusOr<AnalyzeResult> result = Analyze(data, o);
    if (result.ok()) {
      r = CalibrationFrom(result.value(), o.base_effects);
    } else {
      r.error = result.status().message();  // too little or unsuitable data; a solver's failure
    }
  } catch (const Cancelled& e) {  // thrown by the progress callback above
    r = BatchCalibration{};
    r.cancelled = true;
    r.error = e.what();
  }
  r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.sequence = sequence;
  r.num_poses = static_cast<int>(data.poses.size());
  r.num_controls = static_cast<int>(data.controls.size());
  if (!data.poses.empty()) {
    r.data_begin_ns = std::min(data.poses.front().t_ns, data.controls.origin_ns());
    r.data_end_ns = data.poses.back().t_ns;
  }
  return r;
}

bool InlineBatchRunner::Start(int sequence, Recording data, AnalyzeOptions options) {
  if (pending_) return false;
  pending_ = true;
  sequence_ = sequence;
  data_ = std::move(data);
  options_ = std::move(options);
  cancel_running_.store(false);
  return true;
}

std::optional<BatchCalibration> InlineBatchRunner::Poll() {
  if (!pending_) return std::nullopt;
  return Wait();
}

BatchCalibration InlineBatchRunner::Wait() {
  if (!pending_) {
    BatchCalibration r;
    r.error = "no batch was running";
    return r;
  }
  pending_ = false;
  BatchCalibration r = RunBatchCalibration(sequence_, data_, options_, [this]() -> const char* {
    return cancel_running_.load() ? "cancelled: the pipeline is stopping" : nullptr;
  });
  data_ = Recording{};
  return r;
}

std::optional<BatchCalibration> InlineBatchRunner::WaitUnlessCancelled() {
  if (pending_ && cancel_running_.load()) return std::nullopt;
  return Wait();
}

}  // namespace kincal
