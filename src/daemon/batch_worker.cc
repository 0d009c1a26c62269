#include "daemon/batch_worker.h"

#include "daemon/background_thread.h"

namespace kincal::daemon {

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
    const AnalyzeOptions options = options_;
    const int sequence = sequence_;
    lock.unlock();
    BatchCalibration r = RunBatchCalibration(sequence, data, options, [this]() -> const char* {
      if (cancel_.load()) return "cancelled: kincald is being destroyed";
      if (cancel_running_.load()) return "cancelled: kincald is stopping";
      return nullptr;
    });
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

}  // namespace kincal::daemon
