#include "pintag/codec/tag_raster.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <utility>
#include <vector>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/geometry.hpp"
#include "pintag/codec/palette.hpp"

namespace pintag {
namespace {

struct Linear {
  double r = 0;
  double g = 0;
  double b = 0;
};

Linear ToLinear(Rgb8 c) {
  return {SrgbToLinear(c.r), SrgbToLinear(c.g), SrgbToLinear(c.b)};
}

/// geometry::LocateCell without its atan2, which was most of a tag's rendering time: the eighth
/// of the circle from the signs of (dx, up) and which of the two is larger. The regions come from
/// the same expressions; within 1e-9 of a sector boundary (where the two could disagree by a
/// rounding) it asks LocateCell itself, so the answer is LocateCell's everywhere.
geometry::CellAt LocateCellQuickly(double x, double y) {
  if (x < 0 || y < 0 || x >= 1 || y >= 1) return {};
  const int column = x < 0.5 ? 0 : 1;
  const int row = y < 0.5 ? 0 : 1;
  const int element = row == 0 ? column : 3 - column;
  const geometry::Point c = geometry::kElementCentres[element];
  const double dx = x - c.x;
  const double dy = y - c.y;
  const double r2 = dx * dx + dy * dy;
  if (r2 >= geometry::kGreenOuterRadius * geometry::kGreenOuterRadius) {
    return {geometry::Region::kBlack, -1, -1};
  }
  const double up = -dy;
  constexpr double kTie = 1e-9;
  if (std::abs(dx) < kTie || std::abs(up) < kTie || std::abs(std::abs(dx) - std::abs(up)) < kTie) {
    return geometry::LocateCell(x, y);
  }
  // Quadrant clockwise from up, then the vector turned back into the first quadrant, where the
  // angle is past 45 degrees when its right component exceeds its up component.
  int quadrant = 0;
  double right = dx;
  double upward = up;
  if (dx > 0 && up < 0) {
    quadrant = 1, right = -up, upward = dx;
  } else if (dx < 0 && up < 0) {
    quadrant = 2, right = -dx, upward = -up;
  } else if (dx < 0 && up > 0) {
    quadrant = 3, right = up, upward = -dx;
  }
  if (r2 < geometry::kRedRadius * geometry::kRedRadius) {
    return {geometry::Region::kRed, element, quadrant};
  }
  return {geometry::Region::kGreen, element, 2 * quadrant + (right > upward ? 1 : 0)};
}

// Every cell of a tag as a small number: 0 outside the square, 1 black, then the red cells
// (4 per element) and the green cells (8 per element).
constexpr std::uint8_t kOutsideId = 0;
constexpr std::uint8_t kBlackId = 1;
constexpr std::uint8_t kFirstRedId = 2;
constexpr std::uint8_t kFirstGreenId = kFirstRedId + 4 * 4;
constexpr int kCellIds = kFirstGreenId + 4 * 8;
/// A pixel that straddles cells and is supersampled.
constexpr std::uint8_t kBoundaryId = 255;

std::uint8_t CellId(const geometry::CellAt& cell) {
  switch (cell.region) {
    case geometry::Region::kOutside:
      return kOutsideId;
    case geometry::Region::kBlack:
      return kBlackId;
    case geometry::Region::kRed:
      return static_cast<std::uint8_t>(kFirstRedId + 4 * cell.element + cell.index);
    case geometry::Region::kGreen:
      return static_cast<std::uint8_t>(kFirstGreenId + 8 * cell.element + cell.index);
  }
  return kOutsideId;
}

/// The palette colour of every cell id for one key.
std::array<PaletteColour, kCellIds> ColoursOf(const TagCells& cells) {
  std::array<PaletteColour, kCellIds> colours{};
  colours[kOutsideId] = PaletteColour::kWhite;
  colours[kBlackId] = PaletteColour::kBlack;
  for (int element = 0; element < 4; ++element) {
    for (int i = 0; i < 4; ++i) {
      colours[kFirstRedId + 4 * element + i] =
          cells.red[element][i] ? PaletteColour::kRedOne : PaletteColour::kRedZero;
    }
    for (int i = 0; i < 8; ++i) {
      colours[kFirstGreenId + 8 * element + i] =
          cells.green[element][i] ? PaletteColour::kGreenOne : PaletteColour::kGreenZero;
    }
  }
  return colours;
}

/// Which cell covers each pixel of a tag of one size, for any key: the geometry is the same for
/// all 32,768 of them, so it is worked out once per size and kept (TagLayoutFor).
struct TagLayout {
  int side = 0;
  int margin = 0;
  int first = 0;  ///< pixels [first, last] in x and y are drawn; the rest is quiet zone (white)
  int last = -1;
  int samples_per_pixel = 1;
  std::vector<std::uint8_t> ids;  ///< per drawn pixel, row-major: its cell or kBoundaryId
  std::vector<std::uint8_t>
      samples;  ///< per boundary pixel in raster order: its sub-samples' cells
};

TagLayout BuildTagLayout(int n, int ss) {
  TagLayout layout;
  layout.margin = QuietZonePx(n);
  layout.side = n + 2 * layout.margin;
  layout.samples_per_pixel = ss * ss;
  const int margin = layout.margin;
  const double inv_ss = 1.0 / ss;

  // The cell at every pixel corner, two grid rows at a time. A pixel whose four corners lie in the
  // same cell is inside it: cell boundaries are straight lines (square edges, sector rays, which
  // meet only at an element's centre, where the corners fall in four different quadrants) and
  // circles of radius at least 0.1 × kMinTagSquarePx = 6.4 px, which bulge at most 1/(8 × 6.4)
  // = 0.02 px into a pixel between its corners, short of the nearest sub-sample (1/(2 × ss) px
  // in). Only pixels on a boundary, a few percent of the tag, are supersampled.
  // Only grid points within an element's bounding box need classifying: the rest of the square is
  // black and the rest of the image quiet zone (LocateCell says the same there: a point at least
  // the ring's radius from the element centre along x or y is outside the ring).
  const auto fill_corner_row = [&](std::vector<std::uint8_t>& row, int gy, int from, int to) {
    const double v = static_cast<double>(gy - margin) / n;
    const bool in_square_rows = v >= 0 && v < 1;
    for (int gx = from; gx <= to; ++gx) {
      const double u = static_cast<double>(gx - margin) / n;
      row[gx] = in_square_rows && u >= 0 && u < 1 ? kBlackId : kOutsideId;
    }
    if (!in_square_rows) return;
    const double cy = v < 0.5 ? geometry::kElementCentres[0].y : geometry::kElementCentres[3].y;
    if (std::abs(v - cy) >= geometry::kGreenOuterRadius) return;
    for (const double cx : {geometry::kElementCentres[0].x, geometry::kElementCentres[1].x}) {
      const int lo = std::max(
          from, static_cast<int>(std::floor((cx - geometry::kGreenOuterRadius) * n)) + margin);
      const int hi = std::min(
          to, static_cast<int>(std::ceil((cx + geometry::kGreenOuterRadius) * n)) + margin);
      for (int gx = lo; gx <= hi; ++gx) {
        row[gx] = CellId(LocateCellQuickly(static_cast<double>(gx - margin) / n, v));
      }
    }
  };
  // Pixels wholly in the quiet zone are white, as the image starts: only [first, last] is drawn.
  layout.first = std::max(0, margin - 1);
  layout.last = std::min(layout.side - 1, margin + n);
  const int first = layout.first;
  const int last = layout.last;
  const std::size_t drawn = static_cast<std::size_t>(last) - first + 1;
  layout.ids.reserve(drawn * drawn);
  std::vector<std::uint8_t> top(static_cast<std::size_t>(layout.side) + 1);
  std::vector<std::uint8_t> bottom(top.size());
  fill_corner_row(top, first, first, last + 1);
  for (int py = first; py <= last; ++py) {
    fill_corner_row(bottom, py + 1, first, last + 1);
    for (int px = first; px <= last; ++px) {
      const std::uint8_t id = top[px];
      if (id == top[px + 1] && id == bottom[px] && id == bottom[px + 1]) {
        layout.ids.push_back(id);
        continue;
      }
      layout.ids.push_back(kBoundaryId);
      for (int sy = 0; sy < ss; ++sy) {
        const double v = (py - margin + (sy + 0.5) * inv_ss) / n;
        for (int sx = 0; sx < ss; ++sx) {
          const double u = (px - margin + (sx + 0.5) * inv_ss) / n;
          layout.samples.push_back(CellId(LocateCellQuickly(u, v)));
        }
      }
    }
    std::swap(top, bottom);
  }
  return layout;
}

/// The layout for a square of `n` px at `ss` × `ss` sub-samples, from a small process-wide cache:
/// a counter or label server draws the same few sizes all day. The least recently drawn size
/// goes first; sizes past kLargestCached are built per call (a layout is about 1.2 bytes per
/// pixel, 5 MB at 2048 px).
std::shared_ptr<const TagLayout> TagLayoutFor(int n, int ss) {
  constexpr int kLargestCached = 2048;
  constexpr std::size_t kMaxLayouts = 8;
  if (n > kLargestCached) return std::make_shared<const TagLayout>(BuildTagLayout(n, ss));
  using Entry = std::pair<std::pair<int, int>, std::shared_ptr<const TagLayout>>;
  static std::mutex mutex;
  static std::vector<Entry> cache;  // most recently used last
  const std::pair<int, int> size{n, ss};
  const auto take = [&]() -> std::shared_ptr<const TagLayout> {
    const auto found =
        std::find_if(cache.begin(), cache.end(), [&](const Entry& e) { return e.first == size; });
    if (found == cache.end()) return nullptr;
    std::rotate(found, found + 1, cache.end());
    return cache.back().second;
  };
  {
    const std::lock_guard lock(mutex);
    if (auto layout = take()) return layout;
  }
  // Built outside the lock, so other sizes are served meanwhile; a thread that built the same
  // size first wins.
  auto layout = std::make_shared<const TagLayout>(BuildTagLayout(n, ss));
  const std::lock_guard lock(mutex);
  if (auto built = take()) return built;
  if (cache.size() >= kMaxLayouts) cache.erase(cache.begin());
  cache.emplace_back(size, layout);
  return layout;
}

/// The three bit patterns of a linear-light sum, to remember what sRGB colour it averaged to.
struct SumBits {
  std::uint64_t r, g, b;
  bool operator==(const SumBits&) const = default;
};
struct SumBitsHash {
  std::size_t operator()(const SumBits& s) const {
    return std::hash<std::uint64_t>()(s.r ^ (s.g * 0x9E3779B97F4A7C15ULL) ^ (s.b << 1));
  }
};

}  // namespace

int QuietZonePx(int square_px) {
  return static_cast<int>(std::ceil(geometry::kQuietZone * square_px - 1e-9));
}

TagRaster RenderTagRaster(TagKey key, const TagRasterOptions& options) {
  const int n = options.square_px;
  const int ss = options.supersample < 1 ? 1 : options.supersample;
  const std::shared_ptr<const TagLayout> layout = TagLayoutFor(n, ss);
  const std::array<PaletteColour, kCellIds> colour_of = ColoursOf(EncodeCells(key));

  std::array<Linear, kPalette.size()> linear{};
  for (std::size_t i = 0; i < kPalette.size(); ++i) linear[i] = ToLinear(kPalette[i].srgb);

  // Coverage is averaged in linear light, as a camera integrates it over a pixel.
  const double weight = 1.0 / (ss * ss);
  const auto average = [&](const Linear& sum) {
    return Rgb8{LinearToSrgb(sum.r * weight), LinearToSrgb(sum.g * weight),
                LinearToSrgb(sum.b * weight)};
  };
  // A pixel wholly inside one cell gets that cell's colour as the supersampling would compute it
  // (the same sum, in the same order), so skipping the samples changes no pixel.
  std::array<Rgb8, kPalette.size()> uniform{};
  for (std::size_t i = 0; i < kPalette.size(); ++i) {
    Linear sum;
    for (int k = 0; k < ss * ss; ++k) {
      sum.r += linear[i].r;
      sum.g += linear[i].g;
      sum.b += linear[i].b;
    }
    uniform[i] = average(sum);
  }
  // Boundary pixels repeat a few hundred mixtures; each average costs three pow calls.
  std::unordered_map<SumBits, Rgb8, SumBitsHash> averaged;

  TagRaster raster{RgbImage(layout->side, layout->side), layout->margin, n};
  const std::uint8_t* id = layout->ids.data();
  const std::uint8_t* sample = layout->samples.data();
  for (int py = layout->first; py <= layout->last; ++py) {
    for (int px = layout->first; px <= layout->last; ++px, ++id) {
      if (*id != kBoundaryId) {
        raster.image.set(px, py, uniform[static_cast<int>(colour_of[*id])]);
        continue;
      }
      Linear sum;
      for (int k = 0; k < layout->samples_per_pixel; ++k, ++sample) {
        const Linear& c = linear[static_cast<int>(colour_of[*sample])];
        sum.r += c.r;
        sum.g += c.g;
        sum.b += c.b;
      }
      const SumBits bits{std::bit_cast<std::uint64_t>(sum.r), std::bit_cast<std::uint64_t>(sum.g),
                         std::bit_cast<std::uint64_t>(sum.b)};
      auto [entry, added] = averaged.try_emplace(bits);
      if (added) entry->second = average(sum);
      raster.image.set(px, py, entry->second);
    }
  }
  return raster;
}

}  // namespace pintag
