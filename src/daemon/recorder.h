// Recorder: writes a standard LCM event log (readable by lcm-logplayer, lcm-spy and
// `kincald --replay`) from its own thread, so a slow disk never stalls the pipeline.
//
// Producers call Write() from any thread; the message is copied into a recycled buffer
// and queued. Live, a full queue drops the new event and counts it as lost; in lossless
// mode (replay --fast) the producer waits. The file is flushed every `flush_every_s`, so
// after a crash the log reads back to its last whole event. Every event is either
// written or counted in lost().
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "daemon/bounded_queue.h"
#include "kincal/status.h"

namespace kincal::daemon {

class Recorder {
 public:
  struct Item {
    char channel[64] = {};
    int64_t utime = 0;
    std::vector<uint8_t> data;
    size_t size = 0;
  };

  // Creates the log file; an error names the path and errno's text.
  static Status Open(const std::string& path, size_t capacity, FullPolicy policy,
                     double flush_every_s, std::unique_ptr<Recorder>* out);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Copies `n` bytes; false when the event was lost (queue full or recorder closed).
  bool Write(std::string_view channel, int64_t utime, const void* data, size_t n);
  // Encodes an LCM message straight into the queued buffer.
  template <typename Msg>
  bool WriteMessage(std::string_view channel, int64_t utime, const Msg& m) {
    Item& item = Spare();
    const int n = m.getEncodedSize();
    if (item.data.size() < static_cast<size_t>(n)) item.data.resize(static_cast<size_t>(n));
    if (m.encode(item.data.data(), 0, n) != n) {
      lost_.fetch_add(1);
      return false;
    }
    return Enqueue(item, channel, utime, static_cast<size_t>(n));
  }
  // Drains the queue, flushes and closes the file. Idempotent.
  void Close();

  int64_t written() const { return written_.load(); }
  int64_t lost() const { return lost_.load(); }
  const std::string& path() const { return path_; }
  std::string error() const;  // last write error, empty if none

 private:
  Recorder(const std::string& path, void* log, size_t capacity, FullPolicy policy,
           double flush_every_s);
  static Item& Spare();
  bool Enqueue(Item& item, std::string_view channel, int64_t utime, size_t n);
  void Loop();

  std::string path_;
  void* log_ = nullptr;  // lcm_eventlog_t
  BoundedQueue<Item> queue_;
  double flush_every_s_;
  std::atomic<int64_t> written_{0}, lost_{0}, next_eventnum_{0};
  std::atomic<bool> closed_{false};
  mutable std::mutex error_mu_;
  std::string error_;
  std::thread thread_;
};

}  // namespace kincal::daemon
