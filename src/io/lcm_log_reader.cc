#include "kincal/io/lcm_log_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

namespace kincal {
namespace {

constexpr uint32_t kSync = 0xEDA1DA01u;
constexpr int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

uint64_t BigEndian(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

Status LcmLogReader::Open(const std::string& path, std::unique_ptr<LcmLogReader>* out) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return Status::Error(path + ": cannot open the LCM log: " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) {
    return Status::Error(path + ": is a directory, expected an LCM log file");
  }
  if (!S_ISREG(st.st_mode)) {
    return Status::Error(path + ": is not a regular file, expected an LCM log file");
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    return Status::Error(path + ": cannot open the LCM log: " + std::strerror(errno));
  }
  out->reset(new LcmLogReader(path, f, static_cast<int64_t>(st.st_size)));
  return {};
}

LcmLogReader::LcmLogReader(std::string path, std::FILE* f, int64_t size)
    : path_(std::move(path)), f_(f), size_(size) {}

LcmLogReader::~LcmLogReader() {
  if (f_ != nullptr) std::fclose(f_);
}

void LcmLogReader::Rewind() {
  std::fseek(f_, 0, SEEK_SET);
  pos_ = 0;
}

void LcmLogReader::Problem(const std::string& what) {
  if (problems_.size() < 20) problems_.push_back(path_ + ": " + what);
}

// Scans forward from byte `scan` for the next sync word; the bytes from `from` (the start
// of the damaged event) up to it count as damaged.
bool LcmLogReader::Resync(int64_t from, int64_t scan) {
  if (std::fseek(f_, scan, SEEK_SET) != 0) return false;
  uint32_t window = 0;
  int64_t pos = scan;
  for (int c; (c = std::fgetc(f_)) != EOF;) {
    window = (window << 8) | static_cast<uint32_t>(c);
    ++pos;
    if (pos - scan >= 4 && window == kSync) {
      const int64_t start = pos - 4;
      damaged_bytes_ += start - from;
      std::fseek(f_, start, SEEK_SET);
      pos_ = start;
      return true;
    }
  }
  damaged_bytes_ += size_ - from;
  pos_ = size_;
  return false;
}

bool LcmLogReader::Next(LcmLogEvent* ev) {
  while (pos_ < size_) {
    const int64_t start = pos_;
    uint8_t h[kHeaderBytes];
    const int64_t left = size_ - start;
    if (left < kHeaderBytes) {
      // Shorter than a header: a final event cut short (e.g. the logger was killed), or junk.
      truncated_ = true;
      ++damaged_stretches_;
      damaged_bytes_ += left;
      Problem("byte " + std::to_string(start) + ": the last " + std::to_string(left) +
              " bytes are not a whole event header (log cut short); they are lost");
      pos_ = size_;
      return false;
    }
    if (std::fseek(f_, start, SEEK_SET) != 0 ||
        std::fread(h, 1, kHeaderBytes, f_) != kHeaderBytes) {
      Problem("byte " + std::to_string(start) + ": read error");
      pos_ = size_;
      return false;
    }
    const uint32_t sync = static_cast<uint32_t>(BigEndian(h, 4));
    const int64_t eventnum = static_cast<int64_t>(BigEndian(h + 4, 8));
    const int64_t timestamp = static_cast<int64_t>(BigEndian(h + 12, 8));
    const int32_t channel_len = static_cast<int32_t>(BigEndian(h + 20, 4));
    const int32_t data_len = static_cast<int32_t>(BigEndian(h + 24, 4));
    const int64_t body = static_cast<int64_t>(channel_len) + data_len;
    const bool header_ok =
        sync == kSync && channel_len > 0 && channel_len <= kMaxChannelLength && data_len >= 0;
    if (header_ok && body > left - kHeaderBytes) {
      // Consistent header, but the body runs past the end of the file: either the last
      // event was cut short, or a damaged length. A later sync word decides.
      const int64_t before = damaged_bytes_;
      if (!Resync(start, start + 1)) {
        truncated_ = true;
        ++damaged_stretches_;
        Problem("byte " + std::to_string(start) + ": event " + std::to_string(eventnum) +
                " needs " + std::to_string(kHeaderBytes + body) + " bytes but " +
                std::to_string(left) + " remain (log cut short); it is lost");
        return false;
      }
      ++damaged_stretches_;
      Problem("byte " + std::to_string(start) + ": event " + std::to_string(eventnum) + " claims " +
              std::to_string(body) + " bytes, past the end of the file; skipped " +
              std::to_string(damaged_bytes_ - before) + " bytes to the next event");
      continue;
    }
    if (!header_ok) {
      const int64_t before = damaged_bytes_;
      const bool found = Resync(start, start + (sync == kSync ? 1 : 0));
      ++damaged_stretches_;
      Problem("byte " + std::to_string(start) + ": " +
              (sync == kSync ? "event header with channel length " + std::to_string(channel_len) +
                                   " and data length " + std::to_string(data_len) +
                                   " (expected 1-63 and >= 0)"
                             : std::string("expected the sync word 0xEDA1DA01")) +
              "; skipped " + std::to_string(damaged_bytes_ - before) + " bytes" +
              (found ? " to the next event" : " to the end of the file"));
      if (!found) return false;
      continue;
    }
    ev->eventnum = eventnum;
    ev->timestamp = timestamp;
    ev->offset = start;
    ev->channel.resize(static_cast<size_t>(channel_len));
    ev->data.resize(static_cast<size_t>(data_len));
    if (std::fread(ev->channel.data(), 1, ev->channel.size(), f_) != ev->channel.size() ||
        std::fread(ev->data.data(), 1, ev->data.size(), f_) != ev->data.size()) {
      Problem("byte " + std::to_string(start) + ": read error");
      pos_ = size_;
      return false;
    }
    pos_ = start + kHeaderBytes + body;
    return true;
  }
  return false;
}

}  // namespace kincal
