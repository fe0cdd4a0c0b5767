// Status and Result<T>: errors as values. No exception crosses a stage boundary in qnav; a function
// that can fail returns a Status (or a Result<T> holding either a value or a Status). Both are
// [[nodiscard]]. A Status carries a code and a static message (never allocated, never owned).
// Cost: O(1) time, no heap, sizeof(Status) == 2 pointers.
#pragma once

#include <cstdint>
#include <new>
#include <type_traits>
#include <utility>

namespace qnav {

enum class StatusCode : std::uint8_t {
  kOk = 0,
  kInvalidArgument,   // a parameter or input field is out of its valid range (NaN, zero size, ...)
  kOutOfRange,        // an index or coordinate outside a container or image
  kCapacityExceeded,  // a fixed-capacity container or arena is full
  kEmpty,             // nothing to pop / no data
  kNotFound,
  kCorrupt,      // a checksum, magic number or length field does not agree
  kTruncated,    // the input ended inside a record
  kUnsupported,  // a valid input we do not handle (format version, pixel format, ...)
  kIoError,      // an OS or device call failed (only above nav/)
  kTimeout,
  kDegenerate,  // geometry without a unique answer (collinear points, singular matrix, ...)
  kNotReady,
};

constexpr const char* to_string(StatusCode c) noexcept {
  switch (c) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kInvalidArgument: return "invalid argument";
    case StatusCode::kOutOfRange: return "out of range";
    case StatusCode::kCapacityExceeded: return "capacity exceeded";
    case StatusCode::kEmpty: return "empty";
    case StatusCode::kNotFound: return "not found";
    case StatusCode::kCorrupt: return "corrupt";
    case StatusCode::kTruncated: return "truncated";
    case StatusCode::kUnsupported: return "unsupported";
    case StatusCode::kIoError: return "i/o error";
    case StatusCode::kTimeout: return "timeout";
    case StatusCode::kDegenerate: return "degenerate";
    case StatusCode::kNotReady: return "not ready";
  }
  return "unknown";
}

class [[nodiscard]] Status {
 public:
  constexpr Status() noexcept = default;
  // message must have static storage duration (a string literal).
  constexpr Status(StatusCode code, const char* message) noexcept : code_(code), message_(message) {}

  static constexpr Status ok() noexcept { return Status(); }

  constexpr bool is_ok() const noexcept { return code_ == StatusCode::kOk; }
  constexpr explicit operator bool() const noexcept { return is_ok(); }
  constexpr StatusCode code() const noexcept { return code_; }
  constexpr const char* message() const noexcept { return message_ ? message_ : to_string(code_); }

  // For call sites that have handled the outcome by other means (counted it, logged it).
  constexpr void ignore() const noexcept {}

 private:
  StatusCode code_ = StatusCode::kOk;
  const char* message_ = nullptr;
};

constexpr bool operator==(const Status& a, StatusCode c) noexcept { return a.code() == c; }
constexpr bool operator!=(const Status& a, StatusCode c) noexcept { return a.code() != c; }

// Result<T>: either a T or a non-ok Status. value() on an error is a software bug: it traps
// (__builtin_trap) rather than returning garbage, in every build type.
template <typename T>
class [[nodiscard]] Result {
  static_assert(!std::is_reference<T>::value, "Result<T&> is not supported");

 public:
  Result(const T& v) noexcept(std::is_nothrow_copy_constructible<T>::value) : has_value_(true) {  // NOLINT
    new (storage_) T(v);
  }
  Result(T&& v) noexcept(std::is_nothrow_move_constructible<T>::value) : has_value_(true) {  // NOLINT
    new (storage_) T(std::move(v));
  }
  Result(Status s) noexcept : status_(s), has_value_(false) {  // NOLINT
    if (status_.is_ok()) status_ = Status(StatusCode::kInvalidArgument, "Result built from ok Status without a value");
  }
  Result(const Result& o) : status_(o.status_), has_value_(o.has_value_) {
    if (has_value_) new (storage_) T(*o.ptr());
  }
  Result(Result&& o) noexcept(std::is_nothrow_move_constructible<T>::value)
      : status_(o.status_), has_value_(o.has_value_) {
    if (has_value_) new (storage_) T(std::move(*o.ptr()));
  }
  Result& operator=(const Result& o) {
    if (this != &o) {
      reset();
      status_ = o.status_;
      has_value_ = o.has_value_;
      if (has_value_) new (storage_) T(*o.ptr());
    }
    return *this;
  }
  Result& operator=(Result&& o) noexcept(std::is_nothrow_move_constructible<T>::value) {
    if (this != &o) {
      reset();
      status_ = o.status_;
      has_value_ = o.has_value_;
      if (has_value_) new (storage_) T(std::move(*o.ptr()));
    }
    return *this;
  }
  ~Result() { reset(); }

  bool is_ok() const noexcept { return has_value_; }
  explicit operator bool() const noexcept { return has_value_; }
  Status status() const noexcept { return has_value_ ? Status::ok() : status_; }

  T& value() & noexcept {
    if (!has_value_) __builtin_trap();
    return *ptr();
  }
  const T& value() const& noexcept {
    if (!has_value_) __builtin_trap();
    return *ptr();
  }
  T&& value() && noexcept {
    if (!has_value_) __builtin_trap();
    return std::move(*ptr());
  }
  T value_or(T fallback) const { return has_value_ ? *ptr() : fallback; }
  T* operator->() noexcept { return &value(); }
  const T* operator->() const noexcept { return &value(); }
  T& operator*() & noexcept { return value(); }
  const T& operator*() const& noexcept { return value(); }

 private:
  T* ptr() noexcept { return std::launder(static_cast<T*>(static_cast<void*>(storage_))); }
  const T* ptr() const noexcept { return std::launder(static_cast<const T*>(static_cast<const void*>(storage_))); }
  void reset() noexcept {
    if (has_value_) ptr()->~T();
    has_value_ = false;
  }

  alignas(T) unsigned char storage_[sizeof(T)];
  Status status_;
  bool has_value_;
};

}  // namespace qnav

// Propagate a non-ok Status from an expression that yields a Status.
#define QNAV_RETURN_IF_ERROR(expr)                  \
  do {                                              \
    const ::qnav::Status qnav_status_ = (expr);     \
    if (!qnav_status_.is_ok()) return qnav_status_; \
  } while (0)
