#include "daemon/publisher.h"

namespace kincal::daemon {

Status Publisher::Open(const LcmOptions& lcm, const RecordOptions& record, size_t recorder_queue,
                       bool lossless) {
  lcm_ = std::make_unique<lcm::LCM>(lcm.url);
  if (!lcm_->good()) {
    return Status::Error(
        "LCM: cannot open '" + (lcm.url.empty() ? std::string("default URL") : lcm.url) +
        "' (for udpm on loopback: `ip link set lo multicast on` and a 224.0.0.0/4 route)");
  }
  if (record.path.empty()) return {};
  return Recorder::Open(record.path, recorder_queue,
                        lossless ? FullPolicy::kBlock : FullPolicy::kDropNewest,
                        record.flush_every_s, &recorder_);
}

void Publisher::PublishRaw(const std::string& channel, const void* data, size_t n,
                           int64_t log_utime) {
  if (log_utime >= 0) Record(channel, log_utime, data, n);
  if (!lcm_) return;
  std::lock_guard lock(mu_);
  lcm_->publish(channel, data, static_cast<unsigned>(n));
}

void Publisher::Record(const std::string& channel, int64_t utime, const void* data, size_t n) {
  if (recorder_) recorder_->Write(channel, utime, data, n);
}

void Publisher::CloseLog() {
  if (recorder_) recorder_->Close();
}

}  // namespace kincal::daemon
