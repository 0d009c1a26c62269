#include "daemon/guidance.h"

#include "daemon/messages.h"

namespace kincal::daemon {
Guidance::Guidance(const GuidanceOptions& options, Publish publish)
    : opt_(options), publish_(std::move(publish)), thread_([this] { Loop(); }) {}

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

// On the worker thread: the estimate's own system (effects added online included).
void Guidance::Advise(const Checkpoint& estimate) {
  std::string error;
  std::unique_ptr<System> sys;
  PlanOptions o;
  o.info.pose_sigma = Eigen::Vector3d(opt_.pose_sigma[0], opt_.pose_sigma[1], opt_.pose_sigma[2]);
  o.info.pose_rate_hz = opt_.pose_rate_hz;
  Advice a;
  Status s = MakeSystem(estimate.model, estimate.effects, {}, &sys);
  if (s.ok()) s = PlanLimitsFrom(*sys, opt_.limits, opt_.targets, &o);
  if (s.ok() && static_cast<int>(estimate.values.size()) != sys->num_params()) {
    s = Status::Error("the estimate does not match its system");
  }
  if (s.ok()) {
    const Eigen::VectorXd p =
        Eigen::Map<const Eigen::VectorXd>(estimate.values.data(), sys->num_params());
    s = kincal::Advise(*sys, p, estimate.covariance, o, opt_.horizon_s, &a);
  }
  if (!s.ok()) {
    std::lock_guard lock(mu_);
    last_error_ = s.message();
    return;
  }
  kincal::guidance_t m;
  FillGuidanceMessage(*sys, ModelLabel(estimate.model, estimate.effects), a, o, estimate.utime, &m);
  publish_(estimate.utime, m);
  std::lock_guard lock(mu_);
  ++advised_;
}

}  // namespace kincal::daemon
