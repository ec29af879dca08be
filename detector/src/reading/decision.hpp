#pragma once
// When a codeword the model chose is accepted. A misread sends a parcel to the wrong city, so the
// rule is set from measured readings (docs/DETECTOR.md, "How misreads are prevented"): the winner
// must beat every other codeword by a lead in noise units, and explain the samples nearly as well
// as the best labelling found without the code (its colours are ordered as the palette's: the
// search admits no other).

#include <string>

#include "reading/model_reader.hpp"

namespace pintag::reading {

/// Least lead (noise units) of the winner over every other codeword. Set on the tuning world
/// (pintag_reader_probe --world tuning --reader model, seeds 21-23, 48 frames per bin, corners
/// jittered by 0.6 px: 20,160 readings): wrong winners that pass every other check led by up to
/// 122, all in hard light (motion blur, where neighbouring residuals move together and noise
/// units overstate the evidence); 150 keeps 1.23 times that away and refuses 8 % of the right
/// winners in the target bins. Seed 24, checked afterwards, still has one wrong winner at 174:
/// the lead's tail is not bounded by any threshold tried, see docs/DETECTOR.md.
inline constexpr double kMinLead = 150;
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
