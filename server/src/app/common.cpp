#include "app/common.hpp"

#include <charconv>
#include <cmath>
#include <iostream>

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
    case db::ErrorCode::kUnauthorized:
      throw HttpError(401, error.message, std::move(title));
    case db::ErrorCode::kFull:
      throw HttpError(507, error.message, std::move(title));
    case db::ErrorCode::kBusy:
      throw HttpError(503, "the database is busy; try again", "Service Unavailable");
    case db::ErrorCode::kStorage:
      break;
  }
  // Storage failures name files and SQLite internals: the operator sees them, the client not.
  std::cerr << "pintag serve: database error: " << error.message << "\n";
  throw HttpError(500, "the database failed to answer", "Database Error");
}

Pincode ParsePincodeOrThrow(std::string_view text) {
  const ParsedPincode parsed = ParsePincode(text);
  if (!parsed) throw HttpError(400, parsed.error, "Malformed Pincode");
  return *parsed.pincode;
}

long long IntQuery(const server::HttpRequest& request, std::string_view name, long long fallback,
                   long long min, long long max) {
  const std::optional<std::string> text = request.queryParam(name);
  if (!text) return fallback;
  long long value = 0;
  const auto [end, ec] = std::from_chars(text->data(), text->data() + text->size(), value);
  if (ec != std::errc() || end != text->data() + text->size() || value < min || value > max) {
    throw HttpError(400, "query parameter '" + std::string(name) + "' must be an integer from " +
                             std::to_string(min) + " to " + std::to_string(max) + ", got '" +
                             text->substr(0, 40) + "'");
  }
  return value;
}

std::optional<double> NumberQuery(const server::HttpRequest& request, std::string_view name,
                                  double min, double max) {
  const std::optional<std::string> text = request.queryParam(name);
  if (!text) return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(text->data(), text->data() + text->size(), value);
  if (ec != std::errc() || end != text->data() + text->size() || !std::isfinite(value) ||
      value < min || value > max) {
    char range[80];
    std::snprintf(range, sizeof range, "%g to %g", min, max);
    throw HttpError(400, "query parameter '" + std::string(name) + "' must be a number from " +
                             range + ", got '" + text->substr(0, 40) + "'");
  }
  return value;
}

bool BoolQuery(const server::HttpRequest& request, std::string_view name, bool fallback) {
  const std::optional<std::string> text = request.queryParam(name);
  if (!text) return fallback;
  if (*text == "1" || *text == "true" || *text == "yes" || text->empty()) return true;
  if (*text == "0" || *text == "false" || *text == "no") return false;
  throw HttpError(400, "query parameter '" + std::string(name) + "' must be 1 or 0");
}

nlohmann::json JsonBody(const server::HttpRequest& request) {
  nlohmann::json body = nlohmann::json::parse(request.body, nullptr, false);
  if (body.is_discarded()) throw HttpError(400, "the body is not valid JSON", "Malformed JSON");
  return body;
}

const db::PostOffice* MainOffice(const db::PincodeRecord& record) {
  for (const char* type : {"HO", "SO"}) {
    for (const db::PostOffice& office : record.offices) {
      if (office.branch_type == type) return &office;
    }
  }
  return record.offices.empty() ? nullptr : &record.offices.front();
}

namespace {

template <typename T>
nlohmann::json Optional(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json OfficeJson(const db::PostOffice& office, Pincode pincode) {
  return {{"name", office.name},
          {"branch_type", Optional(office.branch_type)},
          {"delivery", Optional(office.delivery)},
          {"circle", office.circle},
          {"region", office.region},
          {"division", office.division},
          {"district", office.district},
          {"state", office.state},
          {"taluk", Optional(office.taluk)},
          {"latitude", Optional(office.latitude)},
          {"longitude", Optional(office.longitude)},
          {"country", "India"},
          {"pincode", pincode.str()}};
}

nlohmann::json RecordJson(const db::PincodeRecord& record) {
  nlohmann::json offices = nlohmann::json::array();
  for (const db::PostOffice& office : record.offices)
    offices.push_back(OfficeJson(office, record.pincode));
  const db::PostOffice* main = MainOffice(record);
  return {{"pincode", record.pincode.str()},
          {"key", record.key.value()},
          {"status", db::ToString(record.status)},
          {"office", main ? nlohmann::json(main->name) : nlohmann::json(nullptr)},
          {"district", record.district},
          {"state", record.state},
          {"circle", record.circle},
          {"region", record.region},
          {"division", record.division},
          {"added_at", record.added_at},
          {"retired_at", Optional(record.retired_at)},
          {"key_allocated_at", record.key_allocated_at},
          {"office_count", record.offices.size()},
          {"offices", std::move(offices)}};
}

}  // namespace pintag::app
