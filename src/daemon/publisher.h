// Where kincald's messages go: LCM (unless a message is for the log only) and, when
// recording, the recorder. Safe to call from every pipeline thread.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <string>

#include "daemon/recorder.h"
#include "kincal/daemon/config.h"
#include "kincal/status.h"

namespace kincal::daemon {

class Publisher {
 public:
  // Opens LCM at lcm.url and, if record.path is set, the recorder (blocking when full if
  // `lossless`, else dropping the newest). An error names the URL or the path.
  Status Open(const LcmOptions& lcm, const RecordOptions& record, size_t recorder_queue,
              bool lossless);

  template <typename Msg>
  void Publish(const std::string& channel, int64_t utime, const Msg& m, bool network = true) {
    if (network && lcm_) {
      std::lock_guard lock(mu_);
      lcm_->publish(channel, &m);
    }
    if (recorder_) recorder_->WriteMessage(channel, utime, m);
  }
  // Raw bytes to LCM, and to the log too when log_utime >= 0 (a simulated robot's
  // controls: LCM only; its truth: both).
  void PublishRaw(const std::string& channel, const void* data, size_t n, int64_t log_utime = -1);
  // Raw bytes to the log only (every control message received).
  void Record(const std::string& channel, int64_t utime, const void* data, size_t n);

  lcm::LCM* lcm() { return lcm_.get(); }
  Recorder* recorder() const { return recorder_.get(); }
  // Drains and closes the log (idempotent).
  void CloseLog();

 private:
  std::unique_ptr<lcm::LCM> lcm_;
  std::mutex mu_;  // lcm::LCM::publish is not thread-safe
  std::unique_ptr<Recorder> recorder_;
};

}  // namespace kincal::daemon
