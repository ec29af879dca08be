#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <set>
#include <string_view>
#include <utility>

#include "label/label_draw.hpp"
#include "label/label_layout.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/png_io.hpp"
#include "pintag/codec/tag_raster.hpp"

namespace pintag {
namespace {

constexpr double kPointsPerMm = kPointsPerInch / kMmPerInch;

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;

cairo_status_t AppendBytes(void* closure, const unsigned char* data, unsigned int length) {
  auto* bytes = static_cast<std::vector<std::uint8_t>*>(closure);
  bytes->insert(bytes->end(), data, data + length);
  return CAIRO_STATUS_SUCCESS;
}

std::string CairoError(const char* what, cairo_status_t status) {
  return std::string(what) + ": " + cairo_status_to_string(status);
}

RenderedLabel Fail(std::string error, std::optional<std::size_t> refused_label = std::nullopt) {
  return {{}, std::move(error), refused_label};
}

// The renderer's own failure (cairo out of memory, the PNG encoder), not the label's.
RenderedLabel InternalFailure(std::string error) {
  return {{}, std::move(error), std::nullopt, true};
}

// The first label whose bin does not print whole and DrawLabel's reason for it, found before any
// page is drawn: a batch refused at its last label drew every page before it for nothing. Each
// distinct bin is tried once, at its first label, on a recording surface that is thrown away (a
// batch's labels mostly share a plan's few bins). The label font's options are its own, so the bin
// is laid out here as on the page.
std::optional<std::pair<std::size_t, std::string>> FirstUnprintableBin(
    std::span<const LabelContent> labels, const label::LabelLayout& layout) {
  Surface scratch(cairo_recording_surface_create(CAIRO_CONTENT_COLOR, nullptr));
  Context cr(cairo_create(scratch.get()));
  cairo_scale(cr.get(), kPointsPerMm, kPointsPerMm);
  std::set<std::optional<std::string>> tried;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (!tried.insert(labels[i].bin).second) continue;
    if (std::string why = label::BinRefusal(cr.get(), labels[i], layout); !why.empty()) {
      return std::pair{i, std::move(why)};
    }
  }
  return std::nullopt;
}

// Draws each label on its own page of a vector surface, then finishes the surface. A label that
// must not be printed ends it, and `refused` says which; any other error is cairo's.
std::string DrawPages(cairo_surface_t* surface, std::span<const LabelContent> labels,
                      const label::LabelLayout& layout, std::optional<std::size_t>* refused) {
  if (labels.size() > 1) {
    if (auto unprintable = FirstUnprintableBin(labels, layout)) {
      *refused = unprintable->first;
      return std::move(unprintable->second);
    }
  }
  Context cr(cairo_create(surface));
  cairo_scale(cr.get(), kPointsPerMm, kPointsPerMm);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (std::string why = label::DrawLabel(cr.get(), labels[i], layout, true); !why.empty()) {
      *refused = i;
      return why;
    }
    cairo_show_page(cr.get());
  }
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
    return CairoError("cannot draw label", cairo_status(cr.get()));
  }
  cr.reset();
  cairo_surface_finish(surface);
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    return CairoError("cannot write label", cairo_surface_status(surface));
  }
  return {};
}

// Cairo 1.16 sizes the document in points ("283.464567pt"), which is exact but reads oddly; its
// millimetre document unit is broken (it writes the point value with "mm"). So the root element's
// width and height are rewritten in millimetres, with the viewBox (points) untouched.
void SizeSvgInMillimetres(std::vector<std::uint8_t>& bytes, const LabelSize& size) {
  std::string text(bytes.begin(), bytes.end());
  const std::size_t svg = text.find("<svg ");
  const std::size_t end = text.find('>', svg);
  if (svg == std::string::npos || end == std::string::npos) return;
  for (const auto& [name, mm] :
       {std::pair{"width=\"", size.width_mm}, {"height=\"", size.height_mm}}) {
    const std::size_t at = text.find(name, svg);
    if (at == std::string::npos || at > end) return;
    const std::size_t from = at + std::strlen(name);
    const std::size_t to = text.find('"', from);
    if (to == std::string::npos || to > end) return;
    char value[32];
    std::snprintf(value, sizeof value, "%.4fmm", mm);
    text.replace(from, to - from, value);
  }
  // cairo names the page's group after a counter of every surface the process has made
  // (`<g id="surface11605">`), so one label drawn twice differed; nothing refers to the id.
  static constexpr std::string_view kGroup = "<g id=\"surface";
  if (const std::size_t group = text.find(kGroup); group != std::string::npos) {
    const std::size_t digits = group + kGroup.size();
    const std::size_t close = text.find('"', digits);
    if (close != std::string::npos) text.replace(digits, close - digits, 1, '1');
  }
  bytes.assign(text.begin(), text.end());
}

}  // namespace

std::string ValidateLabelOptions(const LabelOptions& options, bool raster) {
  std::string error = ValidateLabelSize(options.size);
  if (!error.empty() || !raster) return error;
  if (!std::isfinite(options.dpi) || options.dpi < kMinLabelDpi || options.dpi > kMaxLabelDpi) {
    return "dpi must be " + std::to_string(static_cast<int>(kMinLabelDpi)) + " to " +
           std::to_string(static_cast<int>(kMaxLabelDpi));
  }
  const PixelSize px = LabelPixelSize(options);
  if (static_cast<long long>(px.width) * px.height > kMaxLabelPixels) {
    char dpi[32];
    std::snprintf(dpi, sizeof dpi, "%g", options.dpi);  // 300.7 dpi is not 300
    return "a " + ToString(options.size) + " label at " + dpi + " dpi would be " +
           std::to_string(px.width) + " x " + std::to_string(px.height) + " pixels; the limit is " +
           std::to_string(kMaxLabelPixels / 1'000'000) + " megapixels, lower the dpi";
  }
  return {};
}

PixelSize LabelPixelSize(const LabelOptions& options) {
  const double scale = options.dpi / kMmPerInch;
  return {static_cast<int>(std::lround(options.size.width_mm * scale)),
          static_cast<int>(std::lround(options.size.height_mm * scale))};
}

LabelTagPlacement TagPlacement(const LabelSize& size) {
  return label::ComputeLayout(size).placement;
}

LabelTagPixels TagPlacementPixels(const LabelOptions& options) {
  const LabelTagPlacement p = TagPlacement(options.size);
  const double scale = options.dpi / kMmPerInch;
  return {static_cast<int>(std::lround(p.square_x_mm * scale)),
          static_cast<int>(std::lround(p.square_y_mm * scale)),
          static_cast<int>(std::lround(p.square_side_mm * scale))};
}

namespace {

/// RenderLabelRaster, and `internal` set when the error is the renderer's own (cairo's), not the
/// options' or the label's.
RgbImage RenderRaster(const LabelContent& label, const LabelOptions& options, std::string* error,
                      bool* internal) {
  *internal = false;
  if (std::string why = ValidateLabelOptions(options, true); !why.empty()) {
    *error = std::move(why);
    return {};
  }
  const PixelSize px = LabelPixelSize(options);
  const LabelTagPixels tag = TagPlacementPixels(options);
  // The codec's tag raster (exact coverage, averaged in linear light) is pasted onto the label
  // with its square snapped to whole pixels; below its minimum size cairo draws the tag instead.
  const bool paste_tag = tag.square_side >= kMinTagSquarePx;

  // The cairo surface (4 bytes a pixel) is freed once copied, before the tag's raster is drawn:
  // a 1200 dpi label's peak was the surface, the copy and the tag's raster at once.
  RgbImage image;
  {
    Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, px.width, px.height));
    if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
      *error = CairoError("cannot create label raster", cairo_surface_status(surface.get()));
      *internal = true;
      return {};
    }
    {
      Context cr(cairo_create(surface.get()));
      const double scale = options.dpi / kMmPerInch;
      cairo_scale(cr.get(), scale, scale);
      label::LabelLayout layout = label::ComputeLayout(options.size);
      if (paste_tag) {
        layout.placement = {tag.square_x / scale, tag.square_y / scale, tag.square_side / scale};
      }
      if (std::string refused = label::DrawLabel(cr.get(), label, layout, !paste_tag);
          !refused.empty()) {
        *error = std::move(refused);
        return {};
      }
      if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
        *error = CairoError("cannot draw label", cairo_status(cr.get()));
        *internal = true;
        return {};
      }
    }
    cairo_surface_flush(surface.get());

    // Row pointers rather than a set() per pixel: this copy was an eighth of a 300 dpi label's
    // time.
    image = RgbImage(px.width, px.height);
    const unsigned char* data = cairo_image_surface_get_data(surface.get());
    const int stride = cairo_image_surface_get_stride(surface.get());
    for (int y = 0; y < px.height; ++y) {
      const auto* row =
          reinterpret_cast<const std::uint32_t*>(data + static_cast<std::size_t>(y) * stride);
      std::uint8_t* out = image.pixels.data() + static_cast<std::size_t>(y) * px.width * 3;
      for (int x = 0; x < px.width; ++x, out += 3) {
        const std::uint32_t v = row[x];  // RGB24: 0xXXRRGGBB in native endianness
        out[0] = static_cast<std::uint8_t>(v >> 16);
        out[1] = static_cast<std::uint8_t>(v >> 8);
        out[2] = static_cast<std::uint8_t>(v);
      }
    }
  }

  if (paste_tag) {
    const int supersample = tag.square_side <= 1500 ? 4 : 2;
    const TagRaster raster = RenderTagRaster(label.key, {tag.square_side, supersample});
    const int x0 = tag.square_x - raster.square_origin_px;
    const int y0 = tag.square_y - raster.square_origin_px;
    // The part of the raster inside the label, row by row.
    const int from_x = std::max(0, -x0);
    const int to_x = std::min(raster.image.width, image.width - x0);
    for (int y = std::max(0, -y0); y < std::min(raster.image.height, image.height - y0); ++y) {
      if (to_x <= from_x) break;
      std::memcpy(
          image.pixels.data() + (static_cast<std::size_t>(y0 + y) * image.width + x0 + from_x) * 3,
          raster.image.pixels.data() +
              (static_cast<std::size_t>(y) * raster.image.width + from_x) * 3,
          static_cast<std::size_t>(to_x - from_x) * 3);
    }
  }
  return image;
}

}  // namespace

RgbImage RenderLabelRaster(const LabelContent& label, const LabelOptions& options,
                           std::string* error) {
  bool internal = false;
  return RenderRaster(label, options, error, &internal);
}

RenderedLabel RenderLabelPng(const LabelContent& label, const LabelOptions& options) {
  std::string error;
  bool internal = false;
  const RgbImage image = RenderRaster(label, options, &error, &internal);
  if (!error.empty()) return internal ? InternalFailure(std::move(error)) : Fail(std::move(error));
  std::vector<std::uint8_t> bytes = EncodePng(image, options.dpi, &error);
  if (!error.empty()) return InternalFailure(std::move(error));
  return {std::move(bytes), {}, {}};
}

RenderedLabel RenderLabelsPdf(std::span<const LabelContent> labels, const LabelOptions& options) {
  if (labels.empty()) return Fail("no labels to render");
  if (std::string why = ValidateLabelOptions(options, false); !why.empty()) return Fail(why);
  std::vector<std::uint8_t> bytes;
  Surface surface(cairo_pdf_surface_create_for_stream(AppendBytes, &bytes,
                                                      options.size.width_mm * kPointsPerMm,
                                                      options.size.height_mm * kPointsPerMm));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return InternalFailure(
        CairoError("cannot create label PDF", cairo_surface_status(surface.get())));
  }
  const std::string title = labels.size() == 1
                                ? "PinTag label " + labels.front().pincode.str()
                                : "PinTag labels (" + std::to_string(labels.size()) + ")";
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_TITLE, title.c_str());
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_CREATOR, "PinTag");
  // cairo dates the file when it writes it, so one label gave other bytes every time. An empty
  // date leaves /CreationDate out; cairo 1.16 writes a fixed one without its "D:", malformed.
  cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_CREATE_DATE, "");
  std::optional<std::size_t> refused;
  if (std::string why =
          DrawPages(surface.get(), labels, label::ComputeLayout(options.size), &refused);
      !why.empty()) {
    return refused ? Fail(why, refused) : InternalFailure(why);
  }
  return {std::move(bytes), {}, {}};
}

RenderedLabel RenderLabelPdf(const LabelContent& label, const LabelOptions& options) {
  return RenderLabelsPdf(std::span<const LabelContent>(&label, 1), options);
}

RenderedLabel RenderLabelSvg(const LabelContent& label, const LabelOptions& options) {
  if (std::string why = ValidateLabelOptions(options, false); !why.empty()) return Fail(why);
  std::vector<std::uint8_t> bytes;
  Surface surface(cairo_svg_surface_create_for_stream(AppendBytes, &bytes,
                                                      options.size.width_mm * kPointsPerMm,
                                                      options.size.height_mm * kPointsPerMm));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return InternalFailure(
        CairoError("cannot create label SVG", cairo_surface_status(surface.get())));
  }
  std::optional<std::size_t> refused;
  if (std::string why = DrawPages(surface.get(), std::span<const LabelContent>(&label, 1),
                                  label::ComputeLayout(options.size), &refused);
      !why.empty()) {
    return refused ? Fail(why, refused) : InternalFailure(why);
  }
  SizeSvgInMillimetres(bytes, options.size);
  return {std::move(bytes), {}, {}};
}

}  // namespace pintag
