#pragma once
// Physical label sizes: the dispatch counter's stock (100 × 150 mm, A6, 4 × 6 in) or any W × H
// within explicit limits, parsed from short strings such as "100x150mm", "a6" or "4x6in".

#include <optional>
#include <string>
#include <string_view>

namespace pintag {

/// A label's page in millimetres, width × height (portrait when height > width).
struct LabelSize {
  double width_mm = 100;
  double height_mm = 150;
  constexpr bool operator==(const LabelSize&) const = default;
};

inline constexpr LabelSize kLabel100x150{100, 150};    ///< the default shipping label
inline constexpr LabelSize kLabelA6{105, 148};         ///< ISO A6
inline constexpr LabelSize kLabel4x6In{101.6, 152.4};  ///< 4 × 6 in thermal stock

inline constexpr double kMinLabelSideMm = 50;   ///< smaller labels leave no readable tag
inline constexpr double kMaxLabelSideMm = 300;  ///< larger than any label printer's media
inline constexpr double kMaxLabelAspect = 2.0;  ///< long side / short side, so the layout fits
/// The least black square a label may print: 24 px, the detector's smallest target size, to a
/// phone camera of f = 1500 px at 1.25 m. A size whose layout leaves less is refused.
inline constexpr double kMinLabelTagSideMm = 20;

inline constexpr double kMmPerInch = 25.4;
inline constexpr double kPointsPerInch = 72;  ///< PDF user units: 1 pt = 1/72 in

/// The outcome of parsing a size: a size, or the reason the text is not one.
struct ParsedLabelSize {
  std::optional<LabelSize> size;
  std::string error;  ///< empty when `size` holds a value
  explicit operator bool() const { return size.has_value(); }
};

/// Accepts (case-insensitive, spaces ignored) "a6", "WxHmm", "WxHcm" or "WxHin" with W and H
/// decimal numbers, e.g. "100x150mm", "4x6in", "10.5x14.8cm". A number without a unit is refused
/// (mm or inches would both be plausible). Sides must be kMinLabelSideMm … kMaxLabelSideMm, the
/// aspect ratio at most kMaxLabelAspect, and the layout must leave the tag kMinLabelTagSideMm.
ParsedLabelSize ParseLabelSize(std::string_view text);

/// Empty when `size` is within the limits above, else why not.
std::string ValidateLabelSize(const LabelSize& size);

/// "100x150mm"-style text with six significant digits (for messages), which ParseLabelSize reads
/// back to the same size within a relative 1e-5.
std::string ToString(const LabelSize& size);

}  // namespace pintag
