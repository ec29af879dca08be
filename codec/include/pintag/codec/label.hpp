#pragma once
// Printable shipping labels: the PinTag large, the pincode in large digits, the main office,
// district and state, the sort bin of the chosen plan and the key in small print.
//
// PDF is vector at the exact page size (points, 1 pt = 1/72 in) with subset fonts embedded, one
// page per label, and undated (the same labels are the same bytes); SVG is vector too (cairo SVG
// surface, millimetre document units); PNG is a raster at the asked dpi with the dpi recorded in
// the file. Text is UTF-8 (invalid bytes are replaced, control characters dropped); long names
// shrink to a minimum size and are then ellipsized; a bin that cannot print whole is refused.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "pintag/codec/label_size.hpp"
#include "pintag/codec/pincode.hpp"
#include "pintag/codec/rgb_image.hpp"
#include "pintag/codec/tag_key.hpp"

namespace pintag {

/// What one label says. The caller (registry) resolves pincode -> key, names and bin.
struct LabelContent {
  Pincode pincode{110001};
  TagKey key;
  std::string office;               ///< main office name, e.g. "Connaught Place S.O"; UTF-8
  std::string district;             ///< UTF-8; may be empty
  std::string state;                ///< UTF-8; may be empty
  std::optional<std::string> bin;   ///< sort bin of the chosen plan; none prints "none"
  std::optional<std::string> plan;  ///< name of that plan, printed beside the bin
};

inline constexpr double kMinLabelDpi = 72;
inline constexpr double kMaxLabelDpi = 1200;
inline constexpr long long kMaxLabelPixels = 40'000'000;  ///< raster labels: width × height

/// How labels are drawn. The PDF and SVG ignore `dpi` (they are vector).
struct LabelOptions {
  LabelSize size = kLabel100x150;  ///< page size; see ParseLabelSize
  double dpi = 300;                ///< PNG resolution, kMinLabelDpi … kMaxLabelDpi
};

/// Empty when the options are within the limits (size limits; dpi range; for PNG also the pixel
/// count, see LabelPixelSize), else a message fit to show a user.
std::string ValidateLabelOptions(const LabelOptions& options, bool raster);

struct PixelSize {
  int width = 0;
  int height = 0;
};

/// The PNG's pixel size: each side rounded from mm × dpi / 25.4.
PixelSize LabelPixelSize(const LabelOptions& options);

/// Where the tag sits on a label, in millimetres from the page's top-left corner.
struct LabelTagPlacement {
  double square_x_mm = 0;  ///< the black square's top-left corner
  double square_y_mm = 0;
  double square_side_mm = 0;  ///< the black square's side (the quiet zone is extra, 0.15 × on
                              ///< every side, and lies wholly on the white label)
};

/// The tag's placement for a label size (the same in PDF, SVG and, within half a pixel, PNG).
LabelTagPlacement TagPlacement(const LabelSize& size);

/// The tag's placement in a PNG rendered with `options`, in pixels: the raster renderer snaps the
/// square to whole pixels, so these are exact for sampling the PNG.
struct LabelTagPixels {
  int square_x = 0;
  int square_y = 0;
  int square_side = 0;
};
LabelTagPixels TagPlacementPixels(const LabelOptions& options);

/// Rendered bytes, or an error (bytes empty) fit to show a user.
struct RenderedLabel {
  std::vector<std::uint8_t> bytes;
  std::string error;
  /// Which label (its index in the list given) could not be printed, when that was the error: its
  /// sort bin did not fit whole, or was longer than a label draws.
  std::optional<std::size_t> refused_label;
  /// The error is the renderer's own (cairo out of memory, the PNG encoder failing), not the
  /// options' or the content's: a server's fault, not the request's. False by default.
  bool internal_error = false;
  explicit operator bool() const { return error.empty(); }
};

/// One page PDF (application/pdf).
RenderedLabel RenderLabelPdf(const LabelContent& label, const LabelOptions& options = {});
/// One PDF with a page per label, in order; refuses an empty list.
RenderedLabel RenderLabelsPdf(std::span<const LabelContent> labels,
                              const LabelOptions& options = {});
/// SVG document (image/svg+xml) sized in millimetres.
RenderedLabel RenderLabelSvg(const LabelContent& label, const LabelOptions& options = {});
/// PNG (image/png) at options.dpi, dpi recorded (pHYs).
RenderedLabel RenderLabelPng(const LabelContent& label, const LabelOptions& options = {});

/// The raster behind RenderLabelPng; width and height are LabelPixelSize(options). An empty image
/// and `error` set when the options are out of range.
RgbImage RenderLabelRaster(const LabelContent& label, const LabelOptions& options,
                           std::string* error);

}  // namespace pintag
