#include "daemon/guidance.h"

#include "daemon/background_thread.h"
#include "daemon/messages.h"

namespace kincal::daemon {

Status GuidancePlanningFrom(const GuidanceOptions& g, const Checkpoint& estimate,
                            GuidancePlanning* out) {
  if (Status s = MakeSystem(estimate.model, estimate.effects, {}, &out->sys); !s.ok()) return s;
  if (Status s = PlanLimitsFrom(*out->sys, g.limits, g.targets, &out->options); !s.ok()) return s;
  if (static_cast<int>(estimate.values.size()) != out->sys->num_params()) {
    return Status::Error("the estimate does not match its system");
  }
  out->params = Eigen::Map<const Eigen::VectorXd>(estimate.values.data(), out->sys->num_params());
  out->options.info.pose_sigma = Eigen::Vector3d(g.pose_sigma[0], g.pose_sigma[1], g.pose_sigma[2]);
  out->options.info.pose_rate_hz = g.pose_rate_hz;
  return Status{};
}

Guidance::Guidance(const GuidanceOptions& options, Publish publish, bool background)
    : opt_(options),
      publish_(std::move(publish)),
      background_(background),
      thread_([this] { Loop(); }) {}

Guidance::~Guidance() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void Guidance::Offer(const Checkpoint& estimate) {
  {
    std::lock_guard lock(mu_);
    const int64_t every_us = static_cast<int64_t>(opt_.every_s * 1e6);
    if (offered_ && estimate.utime - last_utime_ < every_us) return;
    if (busy_ || pending_) {
      ++skipped_busy_;
      return;
    }
    offered_ = true;
    last_utime_ = estimate.utime;
    pending_ = estimate;
  }
  cv_.notify_all();
}

void Guidance::Drain() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [this] { return !busy_ && !pending_; });
}

int64_t Guidance::advised() const {
  std::lock_guard lock(mu_);
  return advised_;
}

int64_t Guidance::skipped_busy() const {
  std::lock_guard lock(mu_);
  return skipped_busy_;
}

std::string Guidance::last_error() const {
  std::lock_guard lock(mu_);
  return last_error_;
}

void Guidance::Loop() {
  // Live, advice is seconds of planning: below the pipeline, as the batch worker (at the
  // pipeline's priority it delayed frames by seconds on a loaded 2-core machine). Lossless,
  // the pipeline never idles and a lowered worker would starve: offers would be skipped.
  if (background_) RunThisThreadInTheBackground();
  std::unique_lock lock(mu_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || pending_.has_value(); });
    if (stop_) return;
    const Checkpoint estimate = std::move(*pending_);
    pending_.reset();
    busy_ = true;
    lock.unlock();
    Advise(estimate);
    lock.lock();
    busy_ = false;
    cv_.notify_all();
  }
}

// On the worker thread.
void Guidance::Advise(const Checkpoint& estimate) {
  GuidancePlanning g;
  Advice a;
  Status s = GuidancePlanningFrom(opt_, estimate, &g);
  if (s.ok())
    s = kincal::Advise(*g.sys, g.params, estimate.covariance, g.options, opt_.horizon_s, &a);
  if (!s.ok()) {
    std::lock_guard lock(mu_);
    last_error_ = s.message();
    return;
  }
  kincal::guidance_t m;
  FillGuidanceMessage(*g.sys, ModelLabel(estimate.model, estimate.effects), a, g.options,
                      estimate.utime, &m);
  publish_(estimate.utime, m);
  std::lock_guard lock(mu_);
  ++advised_;
}

}  // namespace kincal::daemon
