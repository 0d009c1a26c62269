#include "daemon/batch_worker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "daemon/background_thread.h"

namespace kincal::daemon {
namespace {

// Thrown from Analyze's progress callback when the worker is destroyed mid-batch; caught
// in Run() below, never outside this file.
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

BatchWorker::BatchWorker(bool background) : thread_([this, background] { Loop(background); }) {}

BatchWorker::~BatchWorker() {
  cancel_.store(true);  // a running batch ends at its next stage (Analyze's progress)
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool BatchWorker::Start(int sequence, Recording data, AnalyzeOptions options) {
  {
    std::lock_guard lock(mu_);
    if (busy_ || pending_) return false;
    sequence_ = sequence;
    cancel_running_.store(false);
    data_ = std::move(data);
    options_ = std::move(options);
    result_.reset();
    pending_ = true;
  }
  cv_.notify_all();
  return true;
}

bool BatchWorker::running() const {
  std::lock_guard lock(mu_);
  return busy_ || pending_;
}

std::optional<BatchCalibration> BatchWorker::Poll() {
  std::lock_guard lock(mu_);
  std::optional<BatchCalibration> r = std::move(result_);
  result_.reset();
  return r;
}

BatchCalibration BatchWorker::Wait() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [this] { return result_.has_value() || (!busy_ && !pending_); });
  BatchCalibration r;
  if (result_) {
    r = std::move(*result_);
  } else {
    r.error = "no batch was running";
  }
  result_.reset();
  return r;
}

void BatchWorker::Loop(bool background) {
  if (background) RunThisThreadInTheBackground();  // below the pipeline (background_thread.h)
  std::unique_lock lock(mu_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || pending_; });
    if (stop_) return;
    pending_ = false;
    busy_ = true;
    const Recording data = std::move(data_);
    AnalyzeOptions options = options_;
    options.progress = [this](double, const std::string&) {
      if (cancel_.load()) throw Cancelled("cancelled: kincald is being destroyed");
      if (cancel_running_.load()) throw Cancelled("cancelled: kincald is stopping");
    };
    const int sequence = sequence_;
    lock.unlock();
    const auto start = std::chrono::steady_clock::now();
    BatchCalibration r = Run(data, options);
    r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.sequence = sequence;
    r.num_poses = static_cast<int>(data.poses.size());
    r.num_controls = static_cast<int>(data.controls.size());
    if (!data.poses.empty()) {
      r.data_begin_ns = std::min(data.poses.front().t_ns, data.controls.origin_ns());
      r.data_end_ns = data.poses.back().t_ns;
    }
    lock.lock();
    busy_ = false;
    result_ = std::move(r);
    cv_.notify_all();
  }
}

void BatchWorker::CancelRunning() {
  {
    std::lock_guard lock(mu_);  // a waiter sees the flag before it sleeps, or is woken
    cancel_running_.store(true);
  }
  cv_.notify_all();
}

std::optional<BatchCalibration> BatchWorker::WaitUnlessCancelled() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [this] {
    return result_.has_value() || (!busy_ && !pending_) || cancel_running_.load();
  });
  if (!result_ && (busy_ || pending_)) return std::nullopt;  // stopping: still running
  lock.unlock();
  return Wait();
}

BatchCalibration BatchWorker::Run(const Recording& data, const AnalyzeOptions& options) {
  try {
    StatusOr<AnalyzeResult> result = Analyze(data, options);
    if (result.ok()) return CalibrationFrom(result.value(), options.base_effects);
    BatchCalibration r;  // too little or unsuitable data; a solver's failure
    r.error = result.status().message();
    return r;
  } catch (const Cancelled& e) {  // thrown by this file's progress callback
    BatchCalibration r;
    r.cancelled = true;
    r.error = e.what();
    return r;
  }
}

}  // namespace kincal::daemon
