#include "daemon/guidance.h"

#include <cmath>
#include <map>

namespace kincal::daemon {
namespace {

// guidance_t.time_to_target_s beyond what the advice predicts (10 minutes).
constexpr double kBeyond = 1e9;

}  // namespace

void FillGuidanceMessage(const System& sys, const Advice& a, const PlanOptions& o, int64_t utime,
                         kincal::guidance_t* m) {
  m->schema_version = 1;
  m->utime = utime;
  m->model = std::string(sys.model().name());
  for (const auto& e : sys.effects()) m->model += "+" + std::string(e->name());
  const int n = sys.num_params();
  m->parameter = a.worst >= 0 ? sys.params()[static_cast<size_t>(a.worst)].name : "";
  m->sigma = a.worst >= 0 ? a.sigma_now[a.worst] : 0.0;
  m->target = a.worst >= 0 && a.worst_ratio > 0.0 ? m->sigma / a.worst_ratio : 0.0;
  m->sigma_after = a.worst >= 0 ? a.sigma_after[a.worst] : 0.0;
  m->motion = a.motion;
  m->duration_s = a.duration_s;
  m->num_controls = sys.num_controls();
  m->control_names.clear();
  for (const auto& c : sys.model().controls()) m->control_names.push_back(c.name);
  m->controls.assign(a.controls.begin(), a.controls.begin() + sys.num_controls());
  m->time_to_target_s = std::isnan(a.time_to_target_s)   ? -1.0
                        : std::isinf(a.time_to_target_s) ? kBeyond
                                                         : a.time_to_target_s;
  m->num_params = n;
  m->names.clear();
  m->sigmas.assign(static_cast<size_t>(n), 0.0);
  m->targets.assign(static_cast<size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    m->names.push_back(sys.params()[static_cast<size_t>(i)].name);
    m->sigmas[static_cast<size_t>(i)] = a.sigma_now[i];
    if (o.targets.size() == n) m->targets[static_cast<size_t>(i)] = o.targets[i];
  }
}

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
  FillGuidanceMessage(*sys, a, o, estimate.utime, &m);
  publish_(estimate.utime, m);
  std::lock_guard lock(mu_);
  ++advised_;
}

}  // namespace kincal::daemon
