#pragma once
// Turns SqliteError into an Error value at the edge of the public API.

#include <exception>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db::detail {

inline Error ToError(const SqliteError& e) {
  if (e.isBusy()) return {ErrorCode::kBusy, e.what()};
  if (e.isConstraint()) return {ErrorCode::kInvalid, e.what()};
  if (e.isFull()) return {ErrorCode::kNoSpace, e.what()};
  if (e.isReadOnly()) return {ErrorCode::kReadOnly, e.what()};
  return {ErrorCode::kStorage, e.what()};
}

/// Runs `body` (which returns a Result) and converts SQLite failures into error values.
template <typename Body>
auto Guard(Body&& body) -> decltype(body()) {
  try {
    return body();
  } catch (const SqliteError& e) {
    return ToError(e);
  }
}

/// The SQL expression for "now" as an ISO 8601 UTC timestamp with milliseconds.
inline constexpr const char* kNowSql = "strftime('%Y-%m-%dT%H:%M:%fZ','now')";

}  // namespace pintag::db::detail
