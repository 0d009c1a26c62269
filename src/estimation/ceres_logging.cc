#include "kincal/estimation/ceres_logging.h"

#include <glog/logging.h>
#include <spdlog/spdlog.h>

#include <mutex>
#include <string_view>

namespace kincal {
namespace {

class SpdlogSink final : public google::LogSink {
 public:
  void send(google::LogSeverity severity, const char*, const char* base_filename, int line,
            const google::LogMessageTime&, const char* message, size_t message_len) override {
    const auto level = severity >= google::GLOG_ERROR ? spdlog::level::warn : spdlog::level::debug;
    spdlog::log(level, "ceres ({}:{}): {}", base_filename, line,
                std::string_view(message, message_len));
  }
};

}  // namespace

void RouteCeresLogging() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (google::IsGoogleLoggingInitialized()) return;
    google::InitGoogleLogging("kincal");
    FLAGS_logtostderr = false;
    FLAGS_alsologtostderr = false;
    FLAGS_stderrthreshold = google::GLOG_FATAL;  // a failed Ceres CHECK still prints
    for (int s = google::GLOG_INFO; s < google::NUM_SEVERITIES; ++s) {
      google::SetLogDestination(s, "");  // no log files
    }
    static SpdlogSink sink;
    google::AddLogSink(&sink);
  });
}

}  // namespace kincal
