// Status and Result<T>: how expected failures travel in thinlod.
//
// Contract:
// - Functions that can fail on untrusted input (files, messages, traces,
//   scene text) return Status or Result<T>; they never throw across a module
//   API or a process boundary.
// - ErrorCode values are stable: protocol/ maps them one-to-one onto the wire.
// - The message is for humans: it names the file/field and the problem, e.g.
//   "cow.obj: face 12 references vertex 9000 (only 2903 vertices)".
// - Programmer errors (violated preconditions) are asserts, not Status.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <variant>

namespace thinlod {

enum class ErrorCode : std::uint8_t {
  kOk = 0,
  kInvalidArgument = 1,  // malformed or out-of-range input value
  kNotFound = 2,         // file, node or object does not exist
  kParseError = 3,       // text input could not be parsed (message has line:col)
  kIoError = 4,          // read/write failure of an existing resource
  kUnsupported = 5,      // valid input we do not handle (format, feature)
  kVersionMismatch = 6,  // stream/file/message version we do not speak
  kUnavailable = 7,      // peer or back-end not reachable right now
  kTimeout = 8,
  kResourceExhausted = 9,  // size limits, budgets
  kInternal = 10,          // a bug: should not happen
};

const char* errorCodeName(ErrorCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;  // OK
  Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status okStatus() { return Status(); }

  bool ok() const { return code_ == ErrorCode::kOk; }
  ErrorCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "ParseError: scene.wrl:3:14: expected '{'"
  std::string toString() const;

 private:
  ErrorCode code_ = ErrorCode::kOk;
  std::string message_;
};

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : storage_(std::move(value)) {}         // NOLINT: implicit by design
  Result(Status status) : storage_(std::move(status)) {}  // NOLINT: must be an error

  bool ok() const { return std::holds_alternative<T>(storage_); }
  const Status& status() const {
    static const Status kOkStatus;
    return ok() ? kOkStatus : std::get<Status>(storage_);
  }
  T& value() & { return std::get<T>(storage_); }
  const T& value() const& { return std::get<T>(storage_); }
  T&& value() && { return std::get<T>(std::move(storage_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::variant<T, Status> storage_;
};

}  // namespace thinlod

// Propagate a non-OK Status from an expression returning Status.
#define THINLOD_RETURN_IF_ERROR(expr)                  \
  do {                                                 \
    ::thinlod::Status thinlod_status_ = (expr);        \
    if (!thinlod_status_.ok()) return thinlod_status_; \
  } while (0)
