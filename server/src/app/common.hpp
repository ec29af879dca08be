#pragma once
// Helpers shared by the application routes: registry errors as problems, registry records as
// JSON, and strict parsing of path and query parameters.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "pintag/codec/pincode.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/result.hpp"
#include "pintag/server/http_types.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {

/// Throws the HttpError for a registry error: kInvalid 400, kNotFound 404, kConflict 409,
/// kUnauthorized 401, kFull 507, kBusy 503, kStorage 500 (its message goes to stderr only).
[[noreturn]] void ThrowDbError(const db::Error& error, std::string title = {});

template <typename T>
T Unwrap(db::Result<T> result, std::string title = {}) {
  if (!result) ThrowDbError(result.error(), std::move(title));
  return std::move(result).value();
}
inline void Unwrap(const db::Result<void>& result, std::string title = {}) {
  if (!result) ThrowDbError(result.error(), std::move(title));
}

/// A six-digit pincode from a path or body; 400 "Malformed Pincode" otherwise.
Pincode ParsePincodeOrThrow(std::string_view text);

/// An integer query parameter within [min, max], or `fallback` when absent; 400 otherwise.
long long IntQuery(const server::HttpRequest& request, std::string_view name, long long fallback,
                   long long min, long long max);
/// A number query parameter within [min, max], if given; 400 otherwise.
std::optional<double> NumberQuery(const server::HttpRequest& request, std::string_view name,
                                  double min, double max);
/// A boolean query parameter ("1", "true", "yes", "0", "false", "no"); 400 otherwise.
bool BoolQuery(const server::HttpRequest& request, std::string_view name, bool fallback);

/// The body parsed as JSON; 400 when it is not.
nlohmann::json JsonBody(const server::HttpRequest& request);

/// The office a label names: the head office, else a sub office, else the first office.
const db::PostOffice* MainOffice(const db::PincodeRecord& record);

nlohmann::json OfficeJson(const db::PostOffice& office, Pincode pincode);
/// A pincode as GET /api/v1/pincodes/{pin} answers it.
nlohmann::json RecordJson(const db::PincodeRecord& record);

}  // namespace pintag::app
