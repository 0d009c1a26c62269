// Length-field checks for LCM messages from outside (see lcm_guard.h). Offsets follow the
// LCM wire format: an 8-byte type hash, then the fields in order, big-endian; a string is
// a 4-byte length (including the terminating NUL) and its bytes.
#include "kincal/io/lcm_guard.h"

#include <cstdint>

namespace kincal {
namespace {

class Reader {
 public:
  Reader(const void* data, size_t n) : p_(static_cast<const uint8_t*>(data)), n_(n) {}
  bool Skip(size_t k) {
    if (k > n_ - pos_) return false;
    pos_ += k;
    return true;
  }
  bool Int32(int64_t* v) {
    if (4 > n_ - pos_) return false;
    *v = static_cast<int32_t>((uint32_t{p_[pos_]} << 24) | (uint32_t{p_[pos_ + 1]} << 16) |
                              (uint32_t{p_[pos_ + 2]} << 8) | uint32_t{p_[pos_ + 3]});
    pos_ += 4;
    return true;
  }
  bool String() {
    int64_t len = 0;
    return Int32(&len) && len >= 1 && Skip(static_cast<size_t>(len));
  }
  size_t remaining() const { return n_ - pos_; }

 private:
  const uint8_t* p_;
  size_t n_;
  size_t pos_ = 0;
};

}  // namespace

bool PlausibleControls(const void* data, size_t n, int max_controls, std::string* why) {
  Reader r(data, n);
  int64_t count = 0;
  // hash, schema_version, utime, sender_utime, model, num_controls
  if (!r.Skip(8 + 4 + 8 + 8) || !r.String() || !r.Int32(&count)) {
    *why = "truncated kincal.controls_t header";
    return false;
  }
  if (count < 0 || count > max_controls) {
    *why = "num_controls " + std::to_string(count) + " outside [0, " +
           std::to_string(max_controls) + "]";
    return false;
  }
  // each control: a name (>= 5 bytes) and a double (8 bytes)
  if (static_cast<size_t>(count) * 13 > r.remaining()) {
    *why = "num_controls " + std::to_string(count) + " does not fit in " + std::to_string(n) +
           " bytes";
    return false;
  }
  // Every string must have a length >= 1 (lcm-gen's decoder subtracts the NUL from it).
  for (int64_t i = 0; i < count; ++i) {
    if (!r.String()) {
      *why = "controls_t.names[" + std::to_string(i) + "] is malformed";
      return false;
    }
  }
  if (!r.Skip(static_cast<size_t>(count) * 8)) {
    *why = "controls_t.values truncated";
    return false;
  }
  return true;
}

bool PlausibleParams(const void* data, size_t n, int max_params, std::string* why) {
  Reader r(data, n);
  int64_t count = 0;
  // hash, schema_version, utime, model, estimator, num_params (strings checked by String())
  if (!r.Skip(8 + 4 + 8) || !r.String() || !r.String() || !r.Int32(&count)) {
    *why = "truncated kincal.params_t header";
    return false;
  }
  if (count < 0 || count > max_params) {
    *why =
        "num_params " + std::to_string(count) + " outside [0, " + std::to_string(max_params) + "]";
    return false;
  }
  // each parameter: name and unit (>= 5 bytes each), value and sigma (8 each), a row of
  // the covariance (8 * count)
  const size_t need = static_cast<size_t>(count) * (5 + 5 + 8 + 8 + 8 * static_cast<size_t>(count));
  if (need > r.remaining()) {
    *why =
        "num_params " + std::to_string(count) + " does not fit in " + std::to_string(n) + " bytes";
    return false;
  }
  for (int64_t i = 0; i < 2 * count; ++i) {  // names, then units
    if (!r.String()) {
      *why = "params_t.names/units[" + std::to_string(i % std::max<int64_t>(count, 1)) +
             "] is malformed";
      return false;
    }
  }
  return true;
}

bool PlausibleFrame(const void* data, size_t n, std::string* why) {
  Reader r(data, n);
  int64_t size = 0;
  // hash, schema_version, utime, device_utime, sequence, width, height, stride, pixel_format, size
  if (!r.Skip(8 + 4 + 8 + 8 + 8 + 4 + 4 + 4) || !r.String() || !r.Int32(&size)) {
    *why = "truncated kincal.frame_t header";
    return false;
  }
  if (size < 0 || static_cast<size_t>(size) != r.remaining()) {
    *why = "frame_t.size " + std::to_string(size) + " but " + std::to_string(r.remaining()) +
           " data bytes";
    return false;
  }
  return true;
}

}  // namespace kincal
