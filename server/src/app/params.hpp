#pragma once
// One parser per kind of parameter, shared by every route: pincodes, keys, token ids, sort plan
// names, label sizes, dpi, numbers and integers within a range, JSON bodies. Each reads
// its text strictly and answers bad input with a 400 problem naming the parameter and what it
// accepts. The OpenAPI notes of the shared query parameters sit beside their parsers.

#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "pintag/codec/label_size.hpp"
#include "pintag/codec/pincode.hpp"
#include "pintag/codec/tag_key.hpp"
#include "pintag/server/http_types.hpp"
#include "pintag/server/router.hpp"

namespace pintag::app {

/// Untrusted text quoted back in a problem ('…'), cut after 40 bytes (at a character's start) so
/// that a huge parameter does not make a huge answer.
std::string Quoted(std::string_view text);

// --- Path parameters -----------------------------------------------------------------------------

/// {pin}: six digits, the first 1-9; else 400 "Malformed Pincode".
Pincode PincodeParam(const server::HttpRequest& request);
/// {key}: 0 to 32767; else 400 "Malformed Key".
TagKey KeyParam(const server::HttpRequest& request);
/// {id}: a token id, a positive integer; else 400.
std::int64_t TokenIdParam(const server::HttpRequest& request);
/// {name}: a sort plan's name, as given (the registry checks it when a plan is written).
std::string PlanNameParam(const server::HttpRequest& request);

// --- Query parameters ----------------------------------------------------------------------------

/// ?plan=: the sort plan whose bins are used; absent or empty: the default plan.
std::string PlanQuery(const server::HttpRequest& request);
server::QueryParamDoc PlanQueryDoc();
server::QueryParamDoc OfficeQueryDoc();  ///< `office` of the label routes

/// ?size=: a label size (100x150mm, a6, 4x6in, WxH mm|cm|in); absent: 100 x 150 mm.
LabelSize LabelSizeQuery(const server::HttpRequest& request);
server::QueryParamDoc LabelSizeQueryDoc();

/// ?dpi=: a PNG's resolution, kMinLabelDpi to kMaxLabelDpi; absent: 300.
double DpiQuery(const server::HttpRequest& request);
server::QueryParamDoc DpiQueryDoc();

/// The whole text as a decimal number, as every route reads one (std::from_chars: no leading
/// '+', no spaces, no hexadecimal), or nothing. `pintag`'s options read numbers with it too.
std::optional<double> ParseDecimal(std::string_view text);
/// A number as the routes' messages show it (printf's %g: 0.001, 1e+07).
std::string ShownNumber(double value);

/// A number within [min, max], if given.
std::optional<double> NumberQuery(const server::HttpRequest& request, std::string_view name,
                                  double min, double max);
/// An integer within [min, max], or `fallback` when absent.
long long IntegerQuery(const server::HttpRequest& request, std::string_view name,
                       long long fallback, long long min, long long max);

// --- Values in a body, or anywhere text arrives --------------------------------------------------

/// How deeply a JSON body's arrays and objects may nest (PinTag's own bodies use at most 4).
inline constexpr std::size_t kMaxJsonDepth = 32;
/// Items (values, counted from the commas and brackets) a JSON body may hold; more answer 413
/// before parsing. A parsed item costs 16–80 bytes, so `[{},{},…]` would grow a 25 MiB body to
/// about a gigabyte, and this many to at most ~20 MB. A pincode with 1,000 offices has ~15,000; a
/// sort plan 3 a rule, so up to ~83,000 rules (a plan for every pincode has ~19,000).
inline constexpr std::size_t kMaxJsonItems = 250'000;
/// The body parsed as JSON; 400 "Malformed JSON" when it is not, nests deeper than
/// kMaxJsonDepth or has a key twice in one object (naming it); 413 when it holds more than
/// kMaxJsonItems.
nlohmann::json JsonBody(const server::HttpRequest& request);
/// The first field of JSON object `object` that `known` does not list, if any: the write routes
/// refuse it, since a misspelt field would otherwise be dropped without a word.
std::optional<std::string> UnknownField(const nlohmann::json& object,
                                        std::initializer_list<std::string_view> known);
/// A pincode given as a JSON string or number; `where` names it in the problem ("pincodes[3]").
Pincode PincodeValue(const nlohmann::json& value, std::string_view where);
/// A label size from its text (empty: the default, 100x150mm); 400 "Bad Label Size".
LabelSize LabelSizeValue(std::string_view text);
/// A sort plan name from a query or a body; empty: the default plan.
std::string PlanNameValue(std::string_view text);

}  // namespace pintag::app
