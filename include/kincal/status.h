// The outcome of an operation on outside data or a device: ok, or an error with a message
// naming what was wrong (a file, field or device, what was expected, and errno's text for a
// failed system call). Bugs are not statuses: they are checked with CHECK-style asserts.
#pragma once

#include <string>
#include <utility>

namespace kincal {

class [[nodiscard]] Status {
 public:
  Status() = default;  // ok
  static Status Error(std::string message) { return Status(std::move(message)); }

  bool ok() const { return !error_; }
  const std::string& message() const { return message_; }

 private:
  explicit Status(std::string message) : error_(true), message_(std::move(message)) {}
  bool error_ = false;
  std::string message_;
};

}  // namespace kincal
