#pragma once
// How India Post's office fields are read, the same from an import and from the API: its words
// for "unknown", and its ways of writing an office type. A type stored as written ("H.O") is not
// recognised as a head office, and the label prints another office.

#include <optional>
#include <string>
#include <string_view>

namespace pintag::db {

/// True for the ways India Post writes "unknown" (NA, N/A, NULL in any case) and for "": an
/// optional field is then left unknown; a required one is refused (CheckOffice), since it would
/// print on labels as a place ("NA, NA").
bool MeansUnknown(std::string_view field);

/// "B.O", "b.o.", " BO" and "BO" are "BO" (likewise SO, HO, PO); any other type is kept as given.
std::optional<std::string> NormalizedOfficeType(std::optional<std::string> type);

}  // namespace pintag::db
