#pragma once
// When a codeword the model chose is accepted. A misread sends a parcel to the wrong city, so the
// rule is set from measured readings (docs/DETECTOR.md, "How misreads are prevented"): the winner
// must beat every other codeword by a lead in noise units, and explain the samples nearly as well
// as the best labelling found without the code (its colours are ordered as the palette's: the
// search admits no other).

#include <string>

#include "reading/model_reader.hpp"

namespace pintag::reading {

/// Least lead (noise units) of the winner over every other codeword.
inline constexpr double kMinLead = 50;
/// Most the winner may explain the samples worse than the best free labelling (noise units).
inline constexpr double kMaxExcess = 20;
/// Least side (px) of a square whose codeword is accepted: below it a cell is under two pixels
/// across and colour (4:2:0) barely one sample.
inline constexpr double kMinSidePx = 16;
/// Least Cr by which both red levels exceed both green ones (the palette's: 0.41).
inline constexpr double kMinRedOverGreenCr = 0.1;

/// Empty when `reading`'s winner is accepted, else why not.
std::string RefuseCodeword(const ModelReading& reading);

}  // namespace pintag::reading
