#pragma once
// Failures as values: every registry query returns Result<T>, a value or an Error.

#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace pintag::db {

/// What went wrong, coarse enough for the server to pick an HTTP status from.
enum class ErrorCode {
  kInvalid,       ///< bad input: malformed pincode, empty or over-long text, bad CSV   (400)
  kNotFound,      ///< no such pincode, key, plan or token                             (404)
  kConflict,      ///< already exists, or the operation contradicts the data           (409)
  kPrecondition,  ///< the stored thing is not in the state the write was made against (412)
  kTooLarge,      ///< over a documented limit, such as the rules of a sort plan       (413)
  kUnauthorized,  ///< token unknown, revoked or wrong secret (one message for all)    (401)
  kFull,          ///< all 32,768 keys are allocated                                   (507)
  kBusy,          ///< the database stayed locked longer than the busy timeout         (503)
  kNoSpace,       ///< the disk holding the database is full; nothing was written       (507)
  kReadOnly,      ///< the database's file or directory cannot be written now           (503)
  kStorage,       ///< any other SQLite or file failure; the message says which        (500)
};

/// "invalid", "not_found", "conflict", "precondition", "too_large",
/// "unauthorized", "full", "busy", "storage".
const char* ToString(ErrorCode code);

struct Error {
  ErrorCode code;
  std::string message;
};

/// A T or an Error. `Result<void>` holds nothing on success.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}  // NOLINT: implicit on purpose
  Result(Error error) : state_(std::move(error)) {}
  Result(ErrorCode code, std::string message) : state_(Error{code, std::move(message)}) {}

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }
  /// Precondition: ok().
  const T& value() const& { return std::get<0>(state_); }
  T& value() & { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  const T& operator*() const& { return value(); }
  const T* operator->() const { return &value(); }
  /// Precondition: !ok().
  const Error& error() const { return std::get<1>(state_); }

 private:
  std::variant<T, Error> state_;
};

template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : error_(std::move(error)) {}
  Result(ErrorCode code, std::string message) : error_(Error{code, std::move(message)}) {}
  bool ok() const { return !error_.has_value(); }
  explicit operator bool() const { return ok(); }
  const Error& error() const { return *error_; }

 private:
  std::optional<Error> error_;
};

}  // namespace pintag::db
