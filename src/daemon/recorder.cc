// LCM event-log writer thread.
#include "daemon/recorder.h"

#include <fcntl.h>
#include <lcm/eventlog.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace kincal::daemon {

Status Recorder::Open(const std::string& path, size_t capacity, FullPolicy policy,
                      double flush_every_s, std::unique_ptr<Recorder>* out) {
  // Created (or truncated) here without following a link, so that liblcm's fopen below
  // writes to a regular file of ours: a link planted at the path is refused, not followed.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    return Status::Error(
        path + ": cannot create LCM log: " + std::strerror(errno) +
        (errno == ELOOP ? " (it is a symbolic link, which kincald never follows)" : ""));
  }
  ::close(fd);
  lcm_eventlog_t* log = lcm_eventlog_create(path.c_str(), "w");
  if (log == nullptr) {
    return Status::Error(path + ": cannot create LCM log: " + std::strerror(errno));
  }
  out->reset(new Recorder(path, log, capacity, policy, flush_every_s));
  return {};
}

Recorder::Recorder(const std::string& path, void* log, size_t capacity, FullPolicy policy,
                   double flush_every_s)
    : path_(path), log_(log), queue_(capacity, policy), flush_every_s_(flush_every_s) {
  thread_ = std::thread([this] { Loop(); });
}

Recorder::~Recorder() { Close(); }

Recorder::Item& Recorder::Spare() {
  thread_local Item spare;
  return spare;
}

bool Recorder::Write(std::string_view channel, int64_t utime, const void* data, size_t n) {
  Item& item = Spare();
  if (item.data.size() < n) item.data.resize(n);
  if (n > 0) std::memcpy(item.data.data(), data, n);
  return Enqueue(item, channel, utime, n);
}

bool Recorder::Enqueue(Item& item, std::string_view channel, int64_t utime, size_t n) {
  if (closed_.load() || channel.size() >= sizeof(item.channel)) {
    lost_.fetch_add(1);
    return false;
  }
  std::memcpy(item.channel, channel.data(), channel.size());
  item.channel[channel.size()] = '\0';
  item.utime = utime;
  item.size = n;
  if (queue_.Push(item)) return true;
  lost_.fetch_add(1);  // queue full (live policy) or closed
  return false;
}

void Recorder::Loop() {
  auto* log = static_cast<lcm_eventlog_t*>(log_);
  Item item;
  auto last_flush = std::chrono::steady_clock::now();
  const auto flush_every = std::chrono::duration<double>(flush_every_s_);
  while (true) {
    const bool got = queue_.Pop(item, std::chrono::milliseconds(50));
    if (got) {
      lcm_eventlog_event_t ev{};
      ev.eventnum = next_eventnum_.fetch_add(1);
      ev.timestamp = item.utime;
      ev.channellen = static_cast<int32_t>(std::strlen(item.channel));
      ev.datalen = static_cast<int32_t>(item.size);
      ev.channel = item.channel;
      ev.data = item.data.data();
      if (lcm_eventlog_write_event(log, &ev) == 0) {
        written_.fetch_add(1);
      } else {
        lost_.fetch_add(1);
        std::lock_guard lock(error_mu_);
        error_ = path_ + ": write failed: " + std::strerror(errno);
      }
    } else if (queue_.closed_and_empty()) {
      break;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now - last_flush >= flush_every) {
      std::fflush(log->f);
      last_flush = now;
    }
  }
  std::fflush(log->f);
}

void Recorder::Close() {
  if (closed_.exchange(true)) return;
  queue_.Close();
  if (thread_.joinable()) thread_.join();
  lcm_eventlog_destroy(static_cast<lcm_eventlog_t*>(log_));
  log_ = nullptr;
}

std::string Recorder::error() const {
  std::lock_guard lock(error_mu_);
  return error_;
}

}  // namespace kincal::daemon
