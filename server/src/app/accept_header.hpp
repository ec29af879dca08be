#pragma once
// Content negotiation by the Accept header (RFC 9110, section 12.5.1): how much a client wants a
// media type, from the most specific range that names it ("text/csv", then "text/*", then
// "*/*") and that range's q weight. Media types and ranges compare case-insensitively.

#include <string_view>

namespace pintag::app {

/// The weight (0 to 1) the header `accept` gives `media_type` ("type/subtype", lower case): 0
/// when no range names it or the naming range says q=0; a malformed weight counts as 1.
double AcceptQuality(std::string_view accept, std::string_view media_type);

}  // namespace pintag::app
