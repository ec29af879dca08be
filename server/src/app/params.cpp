#include "app/params.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <set>
#include <vector>

#include "pintag/codec/label.hpp"
#include "pintag/codec/utf8.hpp"
#include "pintag/db/sort_plan.hpp"
#include "pintag/server/problem.hpp"

namespace pintag::app {

using server::HttpError;
using server::HttpRequest;

std::string Quoted(std::string_view text) {
  return QuotedPrefix(text, 40);
}

namespace {

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// The whole text as a number of type T, or nothing (no sign tricks, spaces or trailing bytes).
template <typename T>
std::optional<T> ParseWhole(std::string_view text) {
  T value{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

}  // namespace

std::optional<double> ParseDecimal(std::string_view text) {
  return ParseWhole<double>(text);
}

std::string ShownNumber(double value) {
  return Number(value);
}

Pincode PincodeParam(const HttpRequest& request) {
  const ParsedPincode parsed = ParsePincode(request.pathParam("pin"));
  if (!parsed) throw HttpError(400, parsed.error, "Malformed Pincode");
  return *parsed.pincode;
}

TagKey KeyParam(const HttpRequest& request) {
  const std::string text = request.pathParam("key");
  const ParsedTagKey parsed = ParseTagKey(text);
  if (!parsed) throw HttpError(400, parsed.error + ", got " + Quoted(text), "Malformed Key");
  return *parsed.key;
}

std::int64_t TokenIdParam(const HttpRequest& request) {
  const std::string text = request.pathParam("id");
  const std::optional<std::int64_t> id = ParseWhole<std::int64_t>(text);
  if (!id || *id <= 0)
    throw HttpError(400, "a token id is a positive integer, got " + Quoted(text));
  return *id;
}

std::string PlanNameParam(const HttpRequest& request) {
  return request.pathParam("name");
}

std::string PlanNameValue(std::string_view text) {
  return text.empty() ? std::string(db::kDefaultPlanName) : std::string(text);
}

std::string PlanQuery(const HttpRequest& request) {
  return PlanNameValue(request.queryParam("plan").value_or(""));
}

server::QueryParamDoc OfficeQueryDoc() {
  return {"office",
          "the office whose name the label prints, one of the pincode's (default: its head "
          "office, else a sub office, else the first)"};
}

server::QueryParamDoc PlanQueryDoc() {
  return {"plan",
          "sort plan whose bins are used (default: " + std::string(db::kDefaultPlanName) + ")"};
}

LabelSize LabelSizeValue(std::string_view text) {
  // Empty is the default, as an empty plan or office is: a form's blank field sends it.
  if (text.empty()) return kLabel100x150;
  const ParsedLabelSize parsed = ParseLabelSize(text);
  if (!parsed) throw HttpError(400, parsed.error, "Bad Label Size");
  return *parsed.size;
}

LabelSize LabelSizeQuery(const HttpRequest& request) {
  const std::optional<std::string> text = request.queryParam("size");
  return text ? LabelSizeValue(*text) : kLabel100x150;
}

server::QueryParamDoc LabelSizeQueryDoc() {
  return {"size",
          "label size: " + ToString(kLabel100x150) + " (default), a6, 4x6in or WxH mm|cm|in"};
}

double DpiQuery(const HttpRequest& request) {
  return NumberQuery(request, "dpi", kMinLabelDpi, kMaxLabelDpi).value_or(LabelOptions{}.dpi);
}

server::QueryParamDoc DpiQueryDoc() {
  return {"dpi",
          "PNG resolution, " + Number(kMinLabelDpi) + " to " + Number(kMaxLabelDpi) + " (default " +
              Number(LabelOptions{}.dpi) + "), recorded in the file",
          "number"};
}

std::optional<double> NumberQuery(const HttpRequest& request, std::string_view name, double min,
                                  double max) {
  const std::optional<std::string> text = request.queryParam(name);
  if (!text) return std::nullopt;
  const std::optional<double> value = ParseWhole<double>(*text);
  if (!value || !std::isfinite(*value) || *value < min || *value > max) {
    throw HttpError(400, "query parameter '" + std::string(name) + "' must be a number from " +
                             Number(min) + " to " + Number(max) + ", got " + Quoted(*text));
  }
  return value;
}

long long IntegerQuery(const HttpRequest& request, std::string_view name, long long fallback,
                       long long min, long long max) {
  const std::optional<std::string> text = request.queryParam(name);
  if (!text) return fallback;
  const std::optional<long long> value = ParseWhole<long long>(*text);
  if (!value || *value < min || *value > max) {
    throw HttpError(400, "query parameter '" + std::string(name) + "' must be an integer from " +
                             std::to_string(min) + " to " + std::to_string(max) + ", got " +
                             Quoted(*text));
  }
  return *value;
}

namespace {

/// How deeply arrays and objects nest in a JSON text, and how many items it holds, counting only
/// brackets and commas outside strings. Bounds for invalid JSON, which the parser then refuses.
struct JsonShape {
  std::size_t depth = 0;  ///< deepest nesting of arrays and objects
  std::size_t items = 0;  ///< an upper bound on the values: commas and opening brackets, plus one
};

JsonShape ShapeOf(std::string_view text) {
  JsonShape shape{0, 1};
  std::size_t depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;  // the escaped character cannot end the string
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      shape.depth = std::max(shape.depth, ++depth);
      ++shape.items;
    } else if (c == ',') {
      ++shape.items;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return shape;
}

}  // namespace

nlohmann::json JsonBody(const HttpRequest& request) {
  // nlohmann::json handles deep nesting with recursion somewhere on its way (a 4 MB body of
  // brackets overflowed a worker's stack and took the server down; found by the ASan suite), and no
  // body PinTag takes nests beyond a few levels.
  const JsonShape shape = ShapeOf(request.body);
  if (shape.depth > kMaxJsonDepth) {
    throw HttpError(400,
                    "the JSON body nests " + std::to_string(shape.depth) +
                        " levels deep; at most " + std::to_string(kMaxJsonDepth) + " allowed",
                    "Malformed JSON");
  }
  // Parsed, each item costs far more than its bytes: refused before parsing, not after.
  if (shape.items > kMaxJsonItems) {
    throw HttpError(413, "the JSON body holds about " + std::to_string(shape.items) +
                             " items; at most " + std::to_string(kMaxJsonItems) + " are read");
  }
  // A key twice in one object: nlohmann keeps the last, so {"pincode": "1…", "pincode": "2…"}
  // would act on one of two values the client sent without a word. Refused instead, naming it.
  std::vector<std::set<std::string>> keys_seen;  // one set per object being parsed
  std::optional<std::string> duplicate;
  const nlohmann::json::parser_callback_t callback =
      [&](int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        using Event = nlohmann::json::parse_event_t;
        if (event == Event::object_start) {
          keys_seen.emplace_back();
        } else if (event == Event::object_end && !keys_seen.empty()) {
          keys_seen.pop_back();
        } else if (event == Event::key && !keys_seen.empty() && !duplicate &&
                   !keys_seen.back().insert(parsed.get<std::string>()).second) {
          duplicate = parsed.get<std::string>();
        }
        return true;
      };
  nlohmann::json body = nlohmann::json::parse(request.body, callback, false);
  if (body.is_discarded()) throw HttpError(400, "the body is not valid JSON", "Malformed JSON");
  if (duplicate) {
    throw HttpError(400,
                    "the key " + Quoted(*duplicate) +
                        " appears twice in one object of the JSON body; give each key once",
                    "Malformed JSON");
  }
  return body;
}

std::optional<std::string> UnknownField(const nlohmann::json& object,
                                        std::initializer_list<std::string_view> known) {
  for (const auto& [field, value] : object.items()) {
    if (std::find(known.begin(), known.end(), field) == known.end()) return field;
  }
  return std::nullopt;
}

Pincode PincodeValue(const nlohmann::json& value, std::string_view where) {
  std::string text;
  if (value.is_string()) {
    text = value.get<std::string>();
  } else if (value.is_number_unsigned()) {
    text = std::to_string(value.get<std::uint64_t>());
  } else {
    throw HttpError(
        400, std::string(where) + " must be six digits, as a string (\"110001\") or a number",
        "Malformed Pincode");
  }
  const ParsedPincode parsed = ParsePincode(text);
  if (!parsed) throw HttpError(400, std::string(where) + ": " + parsed.error, "Malformed Pincode");
  return *parsed.pincode;
}

}  // namespace pintag::app
