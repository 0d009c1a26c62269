// Reader for LCM event logs (the format lcm-logger and kincald write): per event the sync
// word 0xEDA1DA01, the event number (int64), the timestamp (int64, µs, realtime), the
// channel length (int32), the data length (int32), the channel and the data; big-endian.
//
// Written here instead of using liblcm's lcm_eventlog_read_next_event, which allocates
// per event, allocates whatever length a damaged header claims (gigabytes) and ends the
// log silently at the first damaged or truncated event. This reader reuses its buffers,
// checks every length against the bytes left in the file, resynchronises on the next sync
// word after damage and reports what it skipped, and names a truncated last event.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "kincal/status.h"

namespace kincal {

struct LcmLogEvent {
  int64_t eventnum = 0;
  int64_t timestamp = 0;  // µs, as written by the logger (realtime clock)
  int64_t offset = 0;     // byte offset of the event's sync word in the file
  std::string channel;
  std::vector<uint8_t> data;
};

class LcmLogReader {
 public:
  // Largest channel name LCM allows (lcm.h: LCM_MAX_CHANNEL_NAME_LENGTH is 63).
  static constexpr int32_t kMaxChannelLength = 63;

  // Opens a log: an error names the file and why (errno's text; a directory or anything
  // but a regular file is not a log).
  static Status Open(const std::string& path, std::unique_ptr<LcmLogReader>* out);
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  // Reads the next whole event into *ev (its buffers are reused). Returns false at the end
  // of the file. Damaged stretches are skipped (counted in damaged_bytes(), described in
  // problems()); a last event cut short is reported there too and ends the log.
  bool Next(LcmLogEvent* ev);
  // Back to the first byte (for replay loops); the counters keep accumulating.
  void Rewind();

  const std::string& path() const { return path_; }
  int64_t size() const { return size_; }  // bytes
  int64_t damaged_bytes() const { return damaged_bytes_; }
  // Damaged stretches skipped, plus one for a last event cut short.
  int64_t damaged_stretches() const { return damaged_stretches_; }
  bool truncated() const { return truncated_; }
  // One line per problem (the first 20; the counters have the rest), each naming the
  // file and the byte offset.
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  LcmLogReader(std::string path, std::FILE* f, int64_t size);
  bool Resync(int64_t from, int64_t scan);
  void Problem(const std::string& what);

  std::string path_;
  std::FILE* f_ = nullptr;
  int64_t size_ = 0, pos_ = 0;
  int64_t damaged_bytes_ = 0, damaged_stretches_ = 0;
  bool truncated_ = false;
  std::vector<std::string> problems_;
};

}  // namespace kincal
