#include "app/db_problems.hpp"

#include "pintag/server/log.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {

using server::HttpError;

void ThrowDbError(const db::Error& error, std::string title) {
  switch (error.code) {
    case db::ErrorCode::kInvalid:
      throw HttpError(400, error.message, std::move(title));
    case db::ErrorCode::kNotFound:
      throw HttpError(404, error.message, std::move(title));
    case db::ErrorCode::kConflict:
      throw HttpError(409, error.message, std::move(title));
    case db::ErrorCode::kPrecondition:
      throw HttpError(412, error.message, std::move(title));
    case db::ErrorCode::kTooLarge:
      throw HttpError(413, error.message, std::move(title));
    case db::ErrorCode::kUnauthorized:
      throw HttpError(401, error.message, std::move(title));
    case db::ErrorCode::kFull:
      throw HttpError(507, error.message, std::move(title));
    case db::ErrorCode::kBusy:
      // Another writer held the lock past the busy timeout: it passes, so say when to ask again.
      throw HttpError(server::Problem{503, "Database Busy", "the database is busy; try again",
                                      "about:blank", /*retry_after_seconds=*/1});
    case db::ErrorCode::kNoSpace:
      // The client learns what it can act on (try later, tell the operator); the log says where.
      server::LogEvent("database error: " + error.message, /*warning=*/true);
      throw HttpError(507, "the disk holding the database is full; nothing was written",
                      "Insufficient Storage");
    case db::ErrorCode::kReadOnly:
      server::LogEvent("database error: " + error.message, /*warning=*/true);
      throw HttpError(503,
                      "the database cannot be written now (its file or directory is read-only); "
                      "nothing was written",
                      "Service Unavailable");
    case db::ErrorCode::kStorage:
      break;
  }
  // Storage failures name files and SQLite internals: the operator sees them, the client not.
  server::LogEvent("database error: " + error.message, /*warning=*/true);
  throw HttpError(500, "the database failed to answer", "Database Error");
}

void ThrowUnknownPlan(const db::Error& not_found) {
  throw HttpError(404, not_found.message, "Unknown Sort Plan");
}

db::SortPlan LoadPlan(db::Connection& connection, std::string_view name) {
  auto plan = db::GetPlan(connection, name);
  if (!plan && plan.error().code == db::ErrorCode::kNotFound) ThrowUnknownPlan(plan.error());
  return Unwrap(std::move(plan));
}

void RequirePlan(db::Connection& connection, std::string_view name) {
  if (Unwrap(db::HasPlan(connection, name))) return;
  // Read again for the error, which names a plan that reads like `name` (the plan itself would be
  // up to db::kMaxPlanRules rules to read on every scan).
  auto plan = db::GetPlan(connection, name);
  if (!plan && plan.error().code == db::ErrorCode::kNotFound) ThrowUnknownPlan(plan.error());
  Unwrap(std::move(plan));
}

db::Routing RouteUnder(db::Connection& connection, Pincode pincode, std::string_view name) {
  auto routing = db::Route(connection, pincode, name);
  if (!routing && routing.error().code == db::ErrorCode::kNotFound)
    ThrowUnknownPlan(routing.error());
  return Unwrap(std::move(routing));
}

db::PincodeRecord LoadActivePincode(db::Connection& connection, Pincode pincode) {
  db::PincodeRecord record = Unwrap(db::LookupPincode(connection, pincode), "Unknown Pincode");
  if (record.status == db::PincodeStatus::kRetired) {
    throw HttpError(410,
                    "pincode " + pincode.str() + " was retired" +
                        (record.retired_at ? " on " + *record.retired_at : "") +
                        "; no new labels are issued for it (printed labels still decode)",
                    "Retired Pincode");
  }
  return record;
}

}  // namespace pintag::app
