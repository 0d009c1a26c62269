#include "kincal/online/batch_tier.h"

#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

namespace kincal {

bool BatchTierOptions::IsValid(std::string* error) const {
  if (!(every_s >= 1.0) || !(first_s >= 1.0) || !(apply_after_s >= 0.0)) {
    *error = "calibration.every_s and calibration.first_s must be >= 1 s";
    return false;
  }
  if (!(growth >= 0.0)) {
    *error = "calibration.growth must be >= 0";
    return false;
  }
  if (threads < 0 || max_effects < 0) {
    *error = "calibration.threads must be >= 0";
    return false;
  }
  return store.IsValid(error);
}

namespace {

Eigen::MatrixXd Sub(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& idx) {
  const auto k = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd out(k, k);
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b) out(a, b) = m(idx[a], idx[b]);
  }
  return out;
}

// Held parameters (robot.fixed: zero variance) keep this run's value; the free ones are
// fused, and each must have been free in the resumed run too.
bool FreeInBoth(const BatchCalibration& r, const Checkpoint& resumed,
                std::vector<Eigen::Index>* free, std::string* why) {
  for (Eigen::Index i = 0; i < r.covariance.rows(); ++i) {
    if (r.covariance(i, i) <= 0.0) continue;
    if (resumed.covariance(i, i) <= 0.0) {
      *why = "the resumed calibration held " + r.params[static_cast<size_t>(i)].name +
             ", which this run estimates";
      return false;
    }
    free->push_back(i);
  }
  return true;
}

}  // namespace

BatchCalibration FusedWithResumed(const BatchCalibration& r, const Checkpoint& resumed,
                                  std::string* why) {
  const auto n = static_cast<Eigen::Index>(r.params.size());
  bool same = resumed.effects == r.effects && resumed.names.size() == r.params.size() &&
              resumed.covariance.rows() == n && resumed.covariance.cols() == n &&
              r.covariance.rows() == n;
  for (size_t i = 0; same && i < r.params.size(); ++i) same = resumed.names[i] == r.params[i].name;
  if (!same) {
    *why = "the resumed calibration has other parameters or effects";
    return r;
  }
  std::vector<Eigen::Index> free;
  if (!FreeInBoth(r, resumed, &free, why)) return r;
  const auto m = static_cast<Eigen::Index>(free.size());
  const Eigen::LDLT<Eigen::MatrixXd> pb(Sub(r.covariance, free)), pr(Sub(resumed.covariance, free));
  if (m == 0 || pb.info() != Eigen::Success || pr.info() != Eigen::Success || !pb.isPositive() ||
      !pr.isPositive()) {
    *why = m == 0 ? "every parameter is held" : "a covariance is not positive definite";
    return r;
  }
  const Eigen::MatrixXd id = Eigen::MatrixXd::Identity(m, m);
  const Eigen::LDLT<Eigen::MatrixXd> fused(pb.solve(id) + pr.solve(id));
  Eigen::VectorXd xb(m), xr(m);
  for (Eigen::Index k = 0; k < m; ++k) {
    xb[k] = r.params[static_cast<size_t>(free[k])].value;
    xr[k] = resumed.values[static_cast<size_t>(free[k])];
  }
  Eigen::MatrixXd cov = fused.solve(id);
  cov = 0.5 * (cov + cov.transpose()).eval();
  const Eigen::VectorXd x = cov * (pb.solve(xb) + pr.solve(xr));
  BatchCalibration out = r;
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) out.covariance(free[a], free[b]) = cov(a, b);
    out.params[static_cast<size_t>(free[a])].value = x[a];
    out.params[static_cast<size_t>(free[a])].sigma = std::sqrt(cov(a, a));
  }
  out.prior = "fused with the resumed calibration (" +
              (resumed.source == "batch"
                   ? "batch " + std::to_string(resumed.batch_sequence) + " of an earlier run"
                   : std::string("an earlier run's filter estimate")) +
              ")";
  return out;
}

BatchTier::BatchTier(BatchTierOptions options, std::string model, std::vector<std::string> declared,
                     std::map<std::string, double> guess, int num_controls,
                     std::unique_ptr<BatchRunner> runner)
    : opt_(options),
      model_(std::move(model)),
      declared_(std::move(declared)),
      init_(std::move(guess)),
      store_(options.store, num_controls),
      runner_(std::move(runner)),
      next_due_span_ns_(SecondsToNs(options.first_s)) {}

void BatchTier::AddPose(TimeNs t_ns, const Eigen::Vector3d& xytheta) {
  if (opt_.enabled) store_.AddPose(t_ns, xytheta);
}

AnalyzeOptions BatchTier::Options() const {
  AnalyzeOptions o;  // kincal analyze's defaults otherwise
  o.model = model_;
  o.init = init_;
  o.base_effects = declared_;
  o.effects_mode = opt_.auto_effects ? "auto" : "none";
  o.max_effects = opt_.max_effects;
  o.fixed = opt_.fixed;
  o.num_threads = opt_.threads > 0
                      ? opt_.threads
                      : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return o;
}

void BatchTier::StartBatch(TimeNs t_ns) {
  Recording data =
      store_.Snapshot(t_ns, "kincald's run (" + std::to_string(store_.num_poses()) + " poses)");
  if (runner_->Start(sequence_ + 1, std::move(data), Options())) {
    ++sequence_;
    started_span_ns_ = last_span_ns_ = store_.pose_span_ns();
    // Each batch fits the whole span: spacing them by a fraction of it bounds a long
    // run's total batch work to a constant times its last batch's.
    const double gap_s = std::max(opt_.every_s, opt_.growth * NsToSeconds(started_span_ns_));
    next_due_span_ns_ = started_span_ns_ + SecondsToNs(gap_s);
  }
}

// Times on the pipeline's base.
BatchCalibration BatchTier::Finished(BatchCalibration r) const {
  r.data_begin_ns = ToPipeline(r.data_begin_ns);
  r.data_end_ns = ToPipeline(r.data_end_ns);
  return r;
}

std::optional<BatchCalibration> BatchTier::OnPose(TimeNs t_ns) {
  if (!opt_.enabled) return std::nullopt;
  std::optional<BatchCalibration> r;
  if (running()) {
    if (opt_.lossless) {
      // Stopping: the queues drain without waiting; Finish waits for this batch.
      if (!stopping_.load() &&
          store_.pose_span_ns() >= started_span_ns_ + SecondsToNs(opt_.apply_after_s)) {
        r = runner_->WaitUnlessCancelled();
      }
    } else {
      r = runner_->Poll();
    }
    if (r) started_span_ns_ = -1;
    if (r && r->cancelled) {
      last_span_ns_ = -1;  // not fitted after all: Finish fits everything
      r.reset();
    }
  }
  if (!running() && !stopping_.load() && store_.pose_span_ns() >= next_due_span_ns_) {
    StartBatch(t_ns);
  }
  if (r) return Finished(std::move(*r));
  return std::nullopt;
}

std::vector<BatchCalibration> BatchTier::Finish(TimeNs t_ns) {
  std::vector<BatchCalibration> out;
  if (!opt_.enabled || !store_.has_pose()) return out;
  if (running()) {
    BatchCalibration r = runner_->Wait();
    started_span_ns_ = -1;
    if (r.cancelled) {
      last_span_ns_ = -1;  // stopped early (kincald stopping): the batch below replaces it
    } else {
      out.push_back(Finished(std::move(r)));
    }
  }
  if (store_.pose_span_ns() == last_span_ns_) return out;  // the last batch saw it all
  spdlog::info("batch calibration over the whole run ({} poses, {:.0f} s)", store_.num_poses(),
               store_.span_s());
  StartBatch(t_ns);
  if (running()) {
    out.push_back(Finished(runner_->Wait()));
    started_span_ns_ = -1;
  }
  return out;
}

}  // namespace kincal
