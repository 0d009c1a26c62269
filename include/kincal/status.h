// The outcome of an operation on outside data or a device: ok, or an error with a message
// naming what was wrong (a file, field or device, what was expected, and errno's text for a
// failed system call). Bugs are not statuses: they are checked with CHECK-style asserts.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "kincal/check.h"

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

// A value, or the error that stopped it. Reading the value of an error is a bug (checked).
template <typename T>
class [[nodiscard]] StatusOr {
 public:
  StatusOr(T value) : value_(std::move(value)) {}       // NOLINT: implicit, as a return value
  StatusOr(Status error) : status_(std::move(error)) {  // NOLINT
    KINCAL_CHECK(!status_.ok(), "StatusOr made from an ok Status without a value");
  }

  bool ok() const { return status_.ok(); }
  const Status& status() const { return status_; }
  T& value() & {
    KINCAL_CHECK(ok(), status_.message().c_str());
    return *value_;
  }
  const T& value() const& {
    KINCAL_CHECK(ok(), status_.message().c_str());
    return *value_;
  }
  T&& value() && {
    KINCAL_CHECK(ok(), status_.message().c_str());
    return std::move(*value_);
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }

 private:
  Status status_;
  std::optional<T> value_;
};

}  // namespace kincal
