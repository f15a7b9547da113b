// Errors as values (style.md, after MAVSDK/Ceres): bad user input returns a Status that names the
// file, line, key or value; invariants abort loudly instead (MPDRIG_CHECK).
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <variant>

namespace mpdrig {

class [[nodiscard]] Status {
 public:
  // What kind of failure, for callers that react differently (the message is for people).
  enum class Code {
    kOk,
    kError,       // bad input, I/O, solver failure
    kModelRange,  // the simulation left the model's range (e.g. absolute pressure <= 0)
  };

  static Status Ok() { return Status(); }
  static Status Error(std::string message) { return Status(Code::kError, std::move(message)); }
  static Status ModelRangeError(std::string message) {
    return Status(Code::kModelRange, std::move(message));
  }

  bool ok() const { return code_ == Code::kOk; }
  Code code() const { return code_; }
  const std::string& message() const { return message_; }

  // Prefixes context: Status::Error("bad value").Within("rig.pbtxt") -> "rig.pbtxt: bad value".
  Status Within(const std::string& context) const {
    return ok() ? *this : Status(code_, context + ": " + message_);
  }

 private:
  Status() = default;
  Status(Code code, std::string message) : code_(code), message_(std::move(message)) {}
  Code code_ = Code::kOk;
  std::string message_;
};

// A value or the Status that explains why there is none.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}        // NOLINT(google-explicit-constructor)
  Result(Status status) : data_(std::move(status)) {  // NOLINT(google-explicit-constructor)
    if (std::get<Status>(data_).ok()) {
      std::fprintf(stderr, "mpdrig: Result constructed from an OK Status\n");
      std::abort();
    }
  }

  bool ok() const { return std::holds_alternative<T>(data_); }
  Status status() const { return ok() ? Status::Ok() : std::get<Status>(data_); }
  const T& value() const& { return std::get<T>(data_); }
  T& value() & { return std::get<T>(data_); }
  T&& value() && { return std::get<T>(std::move(data_)); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  T&& operator*() && { return std::move(*this).value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

 private:
  std::variant<T, Status> data_;
};

}  // namespace mpdrig

// Invariant check, always armed (also in Release): a violated invariant is a bug in mpdrig, not
// bad input, so it stops the program with the place it failed.
#define MPDRIG_CHECK(condition)                                                              \
  do {                                                                                       \
    if (!(condition)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                          \
    }                                                                                        \
  } while (0)

#define MPDRIG_RETURN_IF_ERROR(expr)   \
  do {                                 \
    ::mpdrig::Status status_ = (expr); \
    if (!status_.ok()) return status_; \
  } while (0)
