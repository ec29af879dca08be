#include "blur_model.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <type_traits>
#include <vector>

#include "homography.hpp"
#include "lab_approx.hpp"
#include "pintag/codec/cielab.hpp"
#include "pintag/codec/geometry.hpp"

namespace pintag::stage {

namespace {

constexpr int kCellsPerElement = kRedQuadrants + kGreenSectors;
constexpr int kRegions = kModelRegions;
constexpr int kOutsideRegion = 0;
constexpr int kBlackRegion = 1;
constexpr int kSubsamples = 4;  // per pixel side, for each pixel's region coverage
constexpr double kMaxSigmaPx = kBlurFitMaxSigmaPx;
constexpr int kMaxKernelRadius = 7;       // px: about 3 kMaxSigmaPx
constexpr double kObservedMargin = 0.06;  // tag units of quiet zone observed beyond the square
constexpr int kSearchPixels = 400;        // pixels used while searching the blur (a stride beyond)
constexpr int kFinalPixels = 2500;        // pixels of the final solve: 50 colours need far fewer
// Pixels per residual in a corner search (brightness only), about. Measured on the benchmark
// (seed 1): 600 found the most tags; 300 one tag fewer, 1,200 one fewer and slower; all three
// channels at 2,500, 3 fewer and slower.
constexpr int kCornerSearchPixels = 600;
constexpr double kRidge = 0.01;  // regularisation, relative to the mean of AᵀA's diagonal
// A nearest codeword that explains the pixels a little worse than the free reading is still
// accepted when its lead is at least this (noise units) and the excess at most this part of it.
constexpr double kMinLeadToExcuseExcess = 100;
constexpr double kMaxExcessPerLead = 0.1;

}  // namespace

// The region of a point in tag units: geometry::LocateCell's answer without its atan2 (this runs
// 16 times per pixel of the tag's surroundings). Sector boundaries are the diagonals and axes, so
// comparisons of the offsets decide them.
int ModelRegionAt(double x, double y) {
  if (x < 0 || y < 0 || x >= 1 || y >= 1) return kOutsideRegion;
  const int column = x < 0.5 ? 0 : 1, row = y < 0.5 ? 0 : 1;
  const int element = row == 0 ? column : 3 - column;
  const geometry::Point c = geometry::kElementCentres[element];
  const double right = x - c.x, up = c.y - y;  // clockwise angles from up
  const double r2 = right * right + up * up;
  constexpr double kOuter2 = geometry::kGreenOuterRadius * geometry::kGreenOuterRadius;
  constexpr double kRed2 = geometry::kRedRadius * geometry::kRedRadius;
  if (r2 >= kOuter2) return kBlackRegion;
  int sector;
  if (right >= 0) {
    sector = up > 0 ? (right < up ? 0 : 1) : (right > -up ? 2 : 3);
  } else {
    sector = up < 0 ? (-right < -up ? 4 : 5) : (-right > up ? 6 : 7);
  }
  const int base = 2 + element * kCellsPerElement;
  return r2 < kRed2 ? base + sector / 2 : base + kRedQuadrants + sector;
}

namespace {

// How much of each region a pixel's area holds (fractions summing to 1).
struct Coverage {
  std::uint32_t first = 0;  // into TagOnGrid::parts_
  std::uint32_t count = 0;
};
struct Part {
  int region;
  float weight;
};
// A pixel wholly in one region, and how many pixels from it rightwards are wholly in that region
// (up to 255); length 0 when the pixel holds more than one region.
struct RegionRun {
  std::uint8_t region = 0;
  std::uint8_t length = 0;
};
static_assert(kModelRegions <= 256);

// The camera's blur by its spread: standard deviations along its long axis and across it, px
// (TagOnGrid::Kernel gives its shape).
struct Blur {
  double major = 1;
  double minor = 1;
  double angle_deg = 0;
  // Extra blur of the colour-difference channels, px: JPEG (and most cameras' video paths) keep
  // colour at half resolution (4:2:0), so colour is blurred more than brightness.
  double chroma_extra = 0.8;
};

// Observations and region colours are modelled as brightness Y and two colour differences
// (B − Y, R − Y) in linear light; Y sees the lens blur, the differences that blur and chroma
// subsampling. The transform is linear, so least squares carries over unchanged.
constexpr double kYr = 0.2126, kYg = 0.7152, kYb = 0.0722;
std::array<double, 3> ToOpponent(double r, double g, double b) {
  const double y = kYr * r + kYg * g + kYb * b;
  return {y, b - y, r - y};
}
std::array<double, 3> ToLinearRgb(const std::array<double, 3>& o) {
  const double y = o[0], b = o[1] + y, r = o[2] + y;
  return {r, (y - kYr * r - kYb * b) / kYg, b};
}

// A spatial hash of an image pixel: picking pixels by it thins them evenly, without the rows or
// columns a linear rule such as x + 3 y would pick for some strides.
std::uint32_t PositionHash(int x, int y) {
  std::uint32_t h =
      static_cast<std::uint32_t>(x) * 73856093U ^ static_cast<std::uint32_t>(y) * 19349663U;
  h ^= h >> 13;
  h *= 0x5bd1e995U;
  return h ^ (h >> 15);
}

// The tag's regions on the pixel grid around it, and the pixels observed.
class TagOnGrid {
 public:
  TagOnGrid(const cv::Mat& bgr, const cv::Matx33d& tag_to_image) {
    const cv::Matx33d to_tag = tag_to_image.inv();
    double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
    for (const double u : {-kObservedMargin, 1 + kObservedMargin}) {
      for (const double v : {-kObservedMargin, 1 + kObservedMargin}) {
        const cv::Vec3d p = tag_to_image * cv::Vec3d(u, v, 1);
        x0 = std::min(x0, p[0] / p[2]), x1 = std::max(x1, p[0] / p[2]);
        y0 = std::min(y0, p[1] / p[2]), y1 = std::max(y1, p[1] / p[2]);
      }
    }
    origin_ = {static_cast<int>(std::floor(x0)) - kMaxKernelRadius,
               static_cast<int>(std::floor(y0)) - kMaxKernelRadius};
    size_ = {static_cast<int>(std::ceil(x1)) + kMaxKernelRadius + 1 - origin_.x,
             static_cast<int>(std::ceil(y1)) + kMaxKernelRadius + 1 - origin_.y};
    coverage_.resize(static_cast<std::size_t>(size_.area()));
    parts_.reserve(coverage_.size() * 2);
    // Pixel corners in tag units, each shared by up to four pixels.
    const auto lattice_width = static_cast<std::size_t>(size_.width) + 1;
    std::vector<PixelCorner> corners(lattice_width * (static_cast<std::size_t>(size_.height) + 1));
    for (int ly = 0; ly <= size_.height; ++ly) {
      for (int lx = 0; lx <= size_.width; ++lx) {
        const double x = static_cast<double>(origin_.x + lx) - 0.5;
        const double y = static_cast<double>(origin_.y + ly) - 0.5;
        const cv::Vec3d t = to_tag * cv::Vec3d(x, y, 1);
        PixelCorner& corner =
            corners[static_cast<std::size_t>(ly) * lattice_width + static_cast<std::size_t>(lx)];
        corner.front = t[2] > 0;
        if (!corner.front) continue;
        corner.u = t[0] / t[2];
        corner.v = t[1] / t[2];
        corner.region = ModelRegionAt(corner.u, corner.v);
      }
    }
    std::array<int, kRegions> hits{};
    for (int gy = 0; gy < size_.height; ++gy) {
      for (int gx = 0; gx < size_.width; ++gx) {
        // Pixel (x, y) has its centre at integer coordinates and covers ±0.5 around it.
        const double x = origin_.x + gx, y = origin_.y + gy;
        // Regions in the order first touched (no allocation: this runs for every pixel of the
        // grid, about a hundred grids per corner fit).
        std::array<int, static_cast<std::size_t>(kSubsamples) * kSubsamples> touched{};
        std::size_t touched_count = 0;
        const std::size_t top_left =
            static_cast<std::size_t>(gy) * lattice_width + static_cast<std::size_t>(gx);
        const std::array<const PixelCorner*, 4> pixel_corners = {
            &corners[top_left], &corners[top_left + 1], &corners[top_left + lattice_width],
            &corners[top_left + lattice_width + 1]};
        // Half the grid is the quiet zone's; much of the rest lies inside one region.
        const int whole_region = WholeRegion(pixel_corners);
        if (whole_region >= 0) {
          hits[whole_region] = kSubsamples * kSubsamples;
          touched[touched_count++] = whole_region;
        }
        for (int sy = 0; sy < kSubsamples && whole_region < 0; ++sy) {
          for (int sx = 0; sx < kSubsamples; ++sx) {
            const double px = x - 0.5 + (sx + 0.5) / kSubsamples;
            const double py = y - 0.5 + (sy + 0.5) / kSubsamples;
            const cv::Vec3d t = to_tag * cv::Vec3d(px, py, 1);
            const int region = ModelRegionAt(t[0] / t[2], t[1] / t[2]);
            if (hits[region]++ == 0) touched[touched_count++] = region;
          }
        }
        Coverage& c = coverage_[index(gx, gy)];
        c.first = static_cast<std::uint32_t>(parts_.size());
        c.count = static_cast<std::uint32_t>(touched_count);
        for (const int region : std::span(touched.data(), touched_count)) {
          parts_.push_back(
              {region, static_cast<float>(hits[region]) / (kSubsamples * kSubsamples)});
          hits[region] = 0;
        }
        // Observed: in the image, a kernel's reach inside the grid, and within the margin.
        if (x < 0 || y < 0 || x >= bgr.cols || y >= bgr.rows || gx < kMaxKernelRadius ||
            gy < kMaxKernelRadius || gx >= size_.width - kMaxKernelRadius ||
            gy >= size_.height - kMaxKernelRadius) {
          continue;
        }
        const cv::Vec3d t = to_tag * cv::Vec3d(x, y, 1);
        const double u = t[0] / t[2], v = t[1] / t[2];
        if (u >= -kObservedMargin && u <= 1 + kObservedMargin && v >= -kObservedMargin &&
            v <= 1 + kObservedMargin) {
          observed_.push_back({gx, gy});
        }
      }
    }
    runs_.resize(coverage_.size());
    for (int gy = 0; gy < size_.height; ++gy) {
      for (int gx = size_.width - 1; gx >= 0; --gx) {
        const Coverage& c = coverage_[index(gx, gy)];
        if (c.count != 1) continue;  // length 0: more than one region
        const auto region = static_cast<std::uint8_t>(parts_[c.first].region);
        int length = 1;
        if (gx + 1 < size_.width) {
          const RegionRun& right = runs_[index(gx + 1, gy)];
          if (right.length > 0 && right.region == region) {
            length = std::min<int>(right.length + 1, std::numeric_limits<std::uint8_t>::max());
          }
        }
        runs_[index(gx, gy)] = {region, static_cast<std::uint8_t>(length)};
      }
    }
    linear_.reserve(observed_.size());
    for (const cv::Point g : observed_) {
      const std::uint8_t* p =
          bgr.ptr<std::uint8_t>(origin_.y + g.y) + 3 * static_cast<std::ptrdiff_t>(origin_.x + g.x);
      linear_.push_back(ToOpponent(SrgbLinear(p[2]), SrgbLinear(p[1]), SrgbLinear(p[0])));
    }
  }

  std::size_t observed() const { return observed_.size(); }

  /// A pixel corner in tag units, and its region (when in front of the camera).
  struct PixelCorner {
    double u = 0, v = 0;
    int region = kOutsideRegion;
    bool front = false;
  };

  /// The one region holding the whole pixel with these corners, or −1 when it may hold more (its
  /// subsamples decide then). With every corner in front of the camera (t₂ > 0) the pixel maps
  /// onto the convex hull of its corners, so: beyond one side of the square (a half-plane) when
  /// all four are; inside a red quadrant (convex) when all four are; inside a green sector or the
  /// black when all four are and a circle around the corners keeps clear of the disks cut out of
  /// that region (the sector's red disk; the black's four element disks).
  static int WholeRegion(const std::array<const PixelCorner*, 4>& corners) {
    constexpr double kMargin = 1e-6;
    std::array<bool, 4> beyond{true, true, true, true};  // u < 0, u > 1, v < 0, v > 1
    double mean_u = 0, mean_v = 0;
    for (const PixelCorner* c : corners) {
      if (!c->front) return -1;
      beyond[0] = beyond[0] && c->u < -kMargin;
      beyond[1] = beyond[1] && c->u > 1 + kMargin;
      beyond[2] = beyond[2] && c->v < -kMargin;
      beyond[3] = beyond[3] && c->v > 1 + kMargin;
      mean_u += c->u / 4, mean_v += c->v / 4;
    }
    if (beyond[0] || beyond[1] || beyond[2] || beyond[3]) return kOutsideRegion;
    const int region = corners[0]->region;
    if (region == kOutsideRegion) return -1;
    for (std::size_t k = 1; k < corners.size(); ++k) {
      if (corners[k]->region != region) return -1;
    }
    const bool red_quadrant =
        region != kBlackRegion && (region - 2) % kCellsPerElement < kRedQuadrants;
    if (red_quadrant) return region;
    double reach2 = 0;  // squared radius of the circle around the corners
    for (const PixelCorner* c : corners) {
      reach2 =
          std::max(reach2, (c->u - mean_u) * (c->u - mean_u) + (c->v - mean_v) * (c->v - mean_v));
    }
    const auto clear_of = [&](int element, double radius) {
      const geometry::Point centre = geometry::kElementCentres[element];
      const double du = mean_u - centre.x, dv = mean_v - centre.y;
      const double gap = radius + std::sqrt(reach2) + kMargin;
      return du * du + dv * dv > gap * gap;
    };
    if (region == kBlackRegion) {
      for (int e = 0; e < kElements; ++e) {
        if (!clear_of(e, geometry::kGreenOuterRadius)) return -1;
      }
      return region;
    }
    return clear_of((region - 2) / kCellsPerElement, geometry::kRedRadius) ? region : -1;
  }

  struct Solution {
    double residual = 1e300;  // sum of squares over the pixels used and the 3 channels
    std::size_t pixels = 0;
    std::array<std::array<double, 3>, kRegions> colour{};
    std::array<double, kRegions> support{};  // AᵀA's diagonal: how much each region was seen
    NormalEquations equations;
  };

  /// Which channels a solve fits: brightness and colour differences see different blurs and are
  /// independent least-squares systems, so either can be fitted alone (its residual and colours).
  enum class Channels { kAll, kBrightness, kColour };

  /// Least-squares region colours under `blur`, from every `stride`-th observed pixel (with
  /// `by_position`, the pixels whose PositionHash is a multiple of `stride`: the same pixels
  /// whatever homography placed the grid), in `channels`.
  Solution solve(const Blur& blur, std::size_t stride, Channels channels = Channels::kAll,
                 bool by_position = false) const {
    // System 0: brightness (channel 0); system 1: the colour differences (channels 1 and 2).
    const int first_system = channels == Channels::kColour ? 1 : 0;
    const int end_system = channels == Channels::kBrightness ? 1 : 2;
    const int first_channel = first_system == 0 ? 0 : 1, end_channel = end_system == 1 ? 1 : 3;
    std::array<std::vector<KernelRow>, 2> kernels;  // luma, chroma
    if (first_system == 0) kernels[0] = KernelRows(Kernel(blur));
    if (end_system == 2) {
      Blur wider = blur;
      wider.major = std::sqrt(blur.major * blur.major + blur.chroma_extra * blur.chroma_extra);
      wider.minor = std::sqrt(blur.minor * blur.minor + blur.chroma_extra * blur.chroma_extra);
      kernels[1] = KernelRows(Kernel(wider));
    }
    using Square = cv::Matx<double, kRegions, kRegions>;
    std::array<Square, 2> ata = {Square::zeros(), Square::zeros()};  // luma, chroma
    cv::Matx<double, kRegions, 3> aty = cv::Matx<double, kRegions, 3>::zeros();
    std::array<double, 3> yty{};
    std::array<double, 3> mean{};
    std::array<std::array<double, kRegions>, 2> row{};
    std::array<std::vector<int>, 2> nonzero;
    Solution s;
    for (std::size_t i = 0; i < observed_.size(); i += by_position ? 1 : stride) {
      const cv::Point g = observed_[i];
      if (by_position && PositionHash(origin_.x + g.x, origin_.y + g.y) % stride != 0) continue;
      const std::array<double, 3>& y = linear_[i];
      for (int system = first_system; system < end_system; ++system) {
        std::array<double, kRegions>& w = row[system];
        std::vector<int>& nz = nonzero[system];
        nz.clear();
        // Every term is positive, so a region's sum is 0 only before its first one.
        const auto add = [&](int region, double term) {
          if (!(term > 0)) return;
          if (w[region] == 0) nz.push_back(region);
          w[region] += term;
        };
        for (const KernelRow& kernel_row : kernels[system]) {
          const std::size_t first = index(g.x + kernel_row.dx_begin, g.y + kernel_row.dy);
          const std::size_t count = kernel_row.weight.size();
          for (std::size_t j = 0; j < count;) {
            const RegionRun run = runs_[first + j];
            if (run.length > 0) {  // a stretch in one region: its weight in one addition
              const std::size_t end = std::min(count, j + run.length);
              add(run.region, kernel_row.prefix[end] - kernel_row.prefix[j]);
              j = end;
              continue;
            }
            const Coverage& c = coverage_[first + j];
            for (std::uint32_t k = 0; k < c.count; ++k) {
              const Part& part = parts_[c.first + k];
              add(part.region, kernel_row.weight[j] * part.weight);
            }
            ++j;
          }
        }
        for (std::size_t a = 0; a < nz.size(); ++a) {
          const int ra = nz[a];
          for (std::size_t b = a; b < nz.size(); ++b) {
            const int rb = nz[b];
            ata[system](std::min(ra, rb), std::max(ra, rb)) += w[ra] * w[rb];
          }
          if (system == 0) {
            aty(ra, 0) += w[ra] * y[0];
          } else {
            aty(ra, 1) += w[ra] * y[1];
            aty(ra, 2) += w[ra] * y[2];
          }
        }
        for (int r : nz) w[r] = 0;
      }
      for (int ch = first_channel; ch < end_channel; ++ch) {
        yty[ch] += y[ch] * y[ch], mean[ch] += y[ch];
      }
      ++s.pixels;
    }
    if (s.pixels == 0) return s;
    for (Square& m : ata) {
      for (int a = 0; a < kRegions; ++a) {
        for (int b = 0; b < a; ++b) m(a, b) = m(b, a);
      }
    }
    for (int r = 0; r < kRegions; ++r) s.support[r] = ata[0](r, r);
    double residual = yty[0] + yty[1] + yty[2];
    for (int system = first_system; system < end_system; ++system) {
      const Square& m0 = ata[system];
      double trace = 0;
      for (int r = 0; r < kRegions; ++r) trace += m0(r, r);
      // A little ridge towards the mean colour keeps regions the pixels barely see from swinging.
      const double ridge = kRidge * trace / kRegions;
      Square m = m0;
      for (int r = 0; r < kRegions; ++r) m(r, r) += ridge;
      const int first = system == 0 ? 0 : 1, count = system == 0 ? 1 : 2;
      for (int ch = first; ch < first + count; ++ch) {
        cv::Matx<double, kRegions, 1> rhs, x;
        for (int r = 0; r < kRegions; ++r) {
          rhs(r) = aty(r, ch) + ridge * mean[ch] / static_cast<double>(s.pixels);
        }
        if (!cv::solve(m, rhs, x, cv::DECOMP_CHOLESKY)) return s;
        // |Ax − y|² = yᵀy − 2 xᵀAᵀy + xᵀAᵀA x.
        const cv::Matx<double, kRegions, 1> ata_x = m0 * x;
        for (int r = 0; r < kRegions; ++r) {
          residual += x(r) * (ata_x(r) - 2 * aty(r, ch));
          s.colour[r][ch] = x(r);
        }
      }
    }
    s.residual = std::max(0.0, residual);
    for (int a = 0; a < kRegions; ++a) {
      for (int b = 0; b < kRegions; ++b) {
        s.equations.ata[a * kRegions + b] = ata[0](a, b);
        s.equations.ata_chroma[a * kRegions + b] = ata[1](a, b);
      }
      for (int ch = 0; ch < 3; ++ch) s.equations.aty[a * 3 + ch] = aty(a, ch);
    }
    s.equations.yty = yty;
    s.equations.pixels = s.pixels;
    return s;
  }

 private:
  std::size_t index(int gx, int gy) const {
    return static_cast<std::size_t>(gy) * static_cast<std::size_t>(size_.width) +
           static_cast<std::size_t>(gx);
  }

  static double SrgbLinear(std::uint8_t code) {
    static const std::array<double, 256> table = [] {
      std::array<double, 256> t{};
      for (int i = 0; i < 256; ++i) t[i] = SrgbToLinear(static_cast<std::uint8_t>(i));
      return t;
    }();
    return table[code];
  }

  // Taps (weights summing to 1) for the blur, small tails dropped. A round blur is a Gaussian
  // (defocus); an elongated one is a round Gaussian of σ = minor swept along a line (motion during
  // the exposure) of the length that gives the same spread along it, √(12 (major² − minor²)): a
  // moving camera smears a point evenly along its path, which a Gaussian of σ = major does not
  // (its tails are longer and its middle peaked). Along the line the weight is the Gaussian's
  // integral over the segment, by erf.
  static std::vector<std::pair<cv::Point, double>> Kernel(const Blur& blur) {
    const double angle = blur.angle_deg * std::numbers::pi / 180;
    const double c = std::cos(angle), s = std::sin(angle);
    const double sigma = blur.minor;
    const double half_line =
        std::sqrt(3 * std::max(0.0, blur.major * blur.major - sigma * sigma));  // L / 2
    const int radius =
        std::min(kMaxKernelRadius, static_cast<int>(std::ceil(half_line + 3 * sigma)));
    const double to_erf = 1 / (std::numbers::sqrt2 * sigma);
    // Mean over the segment of a unit-peak Gaussian; the peak stays near 1 for short lines, so
    // one cut-off drops the tails of both shapes.
    const double line_scale =
        half_line > 1e-6 ? std::sqrt(std::numbers::pi / 2) * sigma / (2 * half_line) : 0;
    std::vector<std::pair<cv::Point, double>> taps;
    double total = 0;
    for (int dy = -radius; dy <= radius; ++dy) {
      for (int dx = -radius; dx <= radius; ++dx) {
        const double along = c * dx + s * dy, across = -s * dx + c * dy;
        double w = std::exp(-0.5 * across * across / (sigma * sigma));
        if (line_scale > 0) {
          w *= line_scale *
               (std::erf((along + half_line) * to_erf) - std::erf((along - half_line) * to_erf));
        } else {
          w *= std::exp(-0.5 * along * along / (sigma * sigma));
        }
        if (w < 2e-3) continue;
        taps.push_back({{dx, dy}, w});
        total += w;
      }
    }
    for (auto& tap : taps) tap.second /= total;
    return taps;
  }

  /// A kernel's taps by rows, each row dense from its first kept tap to its last (0 where one was
  /// dropped), with running sums so that a stretch of pixels lying in one region takes the
  /// stretch's weight in one addition.
  struct KernelRow {
    int dy = 0;
    int dx_begin = 0;
    std::vector<double> weight;  // the tap at dx_begin + j
    std::vector<double> prefix;  // prefix[j]: weight[0] + … + weight[j − 1]
  };
  static std::vector<KernelRow> KernelRows(const std::vector<std::pair<cv::Point, double>>& taps) {
    std::vector<KernelRow> rows;
    for (const auto& [offset, weight] : taps) {  // Kernel() gives them row by row, dx rising
      if (rows.empty() || rows.back().dy != offset.y) rows.push_back({offset.y, offset.x, {}, {}});
      KernelRow& row = rows.back();
      row.weight.resize(static_cast<std::size_t>(offset.x - row.dx_begin), 0.0);
      row.weight.push_back(weight);
    }
    for (KernelRow& row : rows) {
      row.prefix.assign(row.weight.size() + 1, 0.0);
      for (std::size_t j = 0; j < row.weight.size(); ++j) {
        row.prefix[j + 1] = row.prefix[j] + row.weight[j];
      }
    }
    return rows;
  }

  cv::Point origin_;
  cv::Size size_;
  std::vector<Coverage> coverage_;
  std::vector<Part> parts_;
  std::vector<RegionRun> runs_;  // per grid pixel
  std::vector<cv::Point> observed_;
  std::vector<std::array<double, 3>> linear_;
};

CellSample ToSample(const std::array<double, 3>& opponent, double support) {
  CellSample s;
  const std::array<double, 3> linear_rgb = ToLinearRgb(opponent);
  // A cell that no observed pixel sees enough of is unread, not read as its ridge prior.
  if (support < 0.5) return s;
  const LabApprox& lab = LabApprox::Get();
  int a = 0, b = 0;
  lab.abStar(LinearToSrgb(linear_rgb[0]), LinearToSrgb(linear_rgb[1]), LinearToSrgb(linear_rgb[2]),
             &a, &b);
  s.a = static_cast<double>(a) / kLabScale;
  s.b = static_cast<double>(b) / kLabScale;
  s.valid = true;
  return s;
}

}  // namespace

BlurFit FitCellsThroughBlur(const cv::Mat& bgr, const cv::Matx33d& tag_to_image) {
  BlurFit fit;
  const double side = MeanSidePx(tag_to_image);
  if (side > kBlurFitMaxSidePx || side < 8) return fit;
  const TagOnGrid grid(bgr, tag_to_image);
  if (grid.observed() < 64) return fit;
  const std::size_t stride = std::max<std::size_t>(1, grid.observed() / kSearchPixels);

  Blur best;
  double best_residual = 1e300;
  const auto consider = [&](Blur blur) {
    blur.major = std::min(blur.major, kMaxSigmaPx);
    blur.minor = std::min(blur.minor, blur.major);
    ++fit.evaluations;
    const double r = grid.solve(blur, stride, TagOnGrid::Channels::kBrightness).residual;
    if (r < best_residual) best_residual = r, best = blur;
  };
  // Round blurs first, then elongated ones around the best, then small steps.
  for (const double sigma : {0.45, 0.75, 1.1, 1.6, 2.2}) consider({sigma, sigma, 0, 0.8});
  const Blur round = best;
  for (const double angle : {0.0, 45.0, 90.0, 135.0}) {
    consider({round.major * 1.7, round.minor / 1.3, angle, round.chroma_extra});
  }
  for (int pass = 0; pass < 2; ++pass) {
    const Blur centre = best;
    for (const double f : {1.25, 0.8}) {
      consider({centre.major * f, centre.minor, centre.angle_deg, centre.chroma_extra});
      consider({centre.major, centre.minor * f, centre.angle_deg, centre.chroma_extra});
    }
    if (centre.major > centre.minor * 1.1) {
      consider({centre.major, centre.minor, centre.angle_deg + 22.5, centre.chroma_extra});
      consider({centre.major, centre.minor, centre.angle_deg - 22.5, centre.chroma_extra});
    }
  }

  // The lens blur is searched on brightness alone (its edges are sharpest there, and it halves
  // the work); then the colour differences' extra blur, on them alone (the brightness system does
  // not change with it).
  const Blur luma_best = best;
  best_residual = 1e300;
  // Up to 2.7 px: on small tags under strong JPEG (and Bayer demosaicing) the fit chose the
  // widest of 0 … 1.2 on most hard-light frames of the benchmark.
  for (const double extra : {0.0, 0.45, 0.8, 1.2, 1.6, 2.1, 2.7}) {
    Blur b = luma_best;
    b.chroma_extra = extra;
    ++fit.evaluations;
    const double r = grid.solve(b, stride, TagOnGrid::Channels::kColour).residual;
    if (r < best_residual) best_residual = r, best = b;
  }

  const TagOnGrid::Solution s =
      grid.solve(best, std::max<std::size_t>(1, grid.observed() / kFinalPixels));
  if (s.pixels == 0 || s.residual >= 1e299) return fit;
  for (int e = 0; e < kElements; ++e) {
    for (int q = 0; q < kRedQuadrants; ++q) {
      const int r = 2 + e * kCellsPerElement + q;
      fit.cells.red[e][q] = ToSample(s.colour[r], s.support[r]);
    }
    for (int g = 0; g < kGreenSectors; ++g) {
      const int r = 2 + e * kCellsPerElement + kRedQuadrants + g;
      fit.cells.green[e][g] = ToSample(s.colour[r], s.support[r]);
    }
  }
  fit.sigma_major_px = best.major;
  fit.sigma_minor_px = best.minor;
  fit.angle_deg = best.angle_deg;
  fit.chroma_extra_px = best.chroma_extra;
  fit.rms = std::sqrt(s.residual / (3.0 * static_cast<double>(s.pixels)));
  fit.equations = s.equations;
  fit.ok = true;
  return fit;
}

std::size_t CornerSearchStride(double square_area_px) {
  // Observed pixels: the square grown by the observed margin on each side.
  const double observed = square_area_px * (1 + 2 * kObservedMargin) * (1 + 2 * kObservedMargin);
  return std::max<std::size_t>(1, static_cast<std::size_t>(observed / kCornerSearchPixels));
}

double ResidualAtFittedBlur(const cv::Mat& bgr, const cv::Matx33d& tag_to_image, const BlurFit& fit,
                            std::size_t pixel_stride) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (!fit.ok) return kNone;
  const TagOnGrid grid(bgr, tag_to_image);
  if (grid.observed() < 64) return kNone;
  const Blur blur{fit.sigma_major_px, fit.sigma_minor_px, fit.angle_deg, fit.chroma_extra_px};
  const TagOnGrid::Solution s =
      grid.solve(blur, std::max<std::size_t>(1, pixel_stride), TagOnGrid::Channels::kBrightness,
                 /*by_position=*/true);
  if (s.pixels == 0 || s.residual >= 1e299) return kNone;
  return s.residual / static_cast<double>(s.pixels);
}

namespace {

// The six colours of the constrained model, and which one each region takes.
enum Level { kQuietLevel, kBlackLevel, kRed0, kRed1, kGreen0, kGreen1, kLevels };
using Labels = std::array<int, kRegions>;
using Colour = std::array<double, 3>;
using Colours = std::array<Colour, kLevels>;
// Residuals, and the weights they are summed with, per channel (Y, B − Y, R − Y).
using ChannelResiduals = std::array<double, 3>;
using ChannelWeights = std::array<double, 3>;

double Total(const ChannelResiduals& residuals, const ChannelWeights& weights = {1, 1, 1}) {
  return std::max(
      0.0, weights[0] * residuals[0] + weights[1] * residuals[1] + weights[2] * residuals[2]);
}

int RedRegion(int e, int q) {
  return 2 + e * kCellsPerElement + q;
}
int GreenRegion(int e, int s) {
  return 2 + e * kCellsPerElement + kRedQuadrants + s;
}
int Flipped(int level) {
  return level == kRed0 ? kRed1 : level == kRed1 ? kRed0 : level == kGreen0 ? kGreen1 : kGreen0;
}

class ConstrainedModel {
 public:
  explicit ConstrainedModel(const NormalEquations& eq) : eq_(eq) {}

  // Brightness (channel 0) and the colour differences see different blurs.
  double ata(int channel, int j, int k) const {
    return (channel == 0 ? eq_.ata : eq_.ata_chroma)[j * kRegions + k];
  }

  // Least-squares colours for the labels, channel by channel; a level nobody takes stays at zero.
  // With `residuals`, also the residual they leave in each channel, from the labels' own 6 × 6
  // normal equations (yᵀy − 2 xᵀb + xᵀBx) rather than from a second pass over the 50 × 50 ones.
  Colours fitColours(const Labels& labels, ChannelResiduals* residuals = nullptr) const {
    Colours colours{};
    cv::Matx<double, kLevels, kLevels> btb;
    for (int ch = 0; ch < 3; ++ch) {
      // Both colour differences see the same blur, so they share one matrix.
      if (ch < 2) {
        btb = cv::Matx<double, kLevels, kLevels>::zeros();
        for (int j = 0; j < kRegions; ++j) {
          for (int k = 0; k < kRegions; ++k) btb(labels[j], labels[k]) += ata(ch, j, k);
        }
      }
      cv::Matx<double, kLevels, 1> bty = cv::Matx<double, kLevels, 1>::zeros();
      for (int j = 0; j < kRegions; ++j) bty(labels[j]) += eq_.aty[j * 3 + ch];
      cv::Matx<double, kLevels, kLevels> ridged = btb;
      double trace = 0;
      for (int l = 0; l < kLevels; ++l) trace += btb(l, l);
      for (int l = 0; l < kLevels; ++l) ridged(l, l) += 1e-9 * trace + 1e-12;
      cv::Matx<double, kLevels, 1> x;
      cv::solve(ridged, bty, x, cv::DECOMP_CHOLESKY);
      for (int l = 0; l < kLevels; ++l) colours[l][ch] = x(l);
      if (residuals != nullptr) (*residuals)[ch] = eq_.yty[ch] + (x.t() * (btb * x - 2 * bty))(0);
    }
    return colours;
  }

  // Change of the residual if region j took the other colour of its class (colours fixed).
  double flipCost(const Labels& labels, const Colours& colours, int j) const {
    const Colour& now = colours[labels[j]];
    const Colour& other = colours[Flipped(labels[j])];
    double cost = 0;
    for (int ch = 0; ch < 3; ++ch) {
      const double d = other[ch] - now[ch];
      double g = 0;
      for (int k = 0; k < kRegions; ++k) g += ata(ch, j, k) * colours[labels[k]][ch];
      cost += d * (2 * g - 2 * eq_.aty[j * 3 + ch] + d * ata(ch, j, j));
    }
    return cost;
  }

  // Iterated conditional modes: flip any free cell that lowers the residual, refit the colours,
  // until nothing changes.
  void settle(Labels* labels, const std::array<bool, kRegions>& fixed, Colours* colours) const {
    *colours = fitColours(*labels);
    for (int round = 0; round < 8; ++round) {
      bool changed = false;
      for (int sweep = 0; sweep < 8; ++sweep) {
        bool flipped = false;
        for (int j = 2; j < kRegions; ++j) {
          if (fixed[j] || flipCost(*labels, *colours, j) >= 0) continue;
          (*labels)[j] = Flipped((*labels)[j]);
          flipped = changed = true;
        }
        if (!flipped) break;
      }
      if (!changed) break;
      *colours = fitColours(*labels);
    }
  }

 private:
  const NormalEquations& eq_;
};

double Bstar(const Colour& opponent) {
  const Colour linear = ToLinearRgb(opponent);
  int a = 0, b = 0;
  LabApprox::Get().abStar(LinearToSrgb(linear[0]), LinearToSrgb(linear[1]), LinearToSrgb(linear[2]),
                          &a, &b);
  return static_cast<double>(b) / kLabScale;
}

}  // namespace

namespace {

using Hypothesis = SettledOrientation;
static_assert(std::is_same_v<decltype(Hypothesis::labels), Labels> &&
              std::is_same_v<decltype(Hypothesis::colours), Colours>);

// For each of the four orientations: the orientation cells fixed to the format's bits, the other
// cells settled by iterated conditional modes.
std::array<Hypothesis, 4> Settle(const ConstrainedModel& model, const BlurFit& fit) {
  std::array<Hypothesis, 4> settled;
  for (int r = 0; r < 4; ++r) {
    // Sampled element (e + r) % 4 is canonical element e; quadrants turn with it.
    Labels labels{};
    std::array<bool, kRegions> fixed{};
    labels[0] = kQuietLevel, labels[1] = kBlackLevel;
    fixed[0] = fixed[1] = true;
    std::vector<double> ones, zeros;
    for (int e = 0; e < kElements; ++e) {
      for (int q = 0; q < kRedQuadrants; ++q) {
        if (q == InnerQuadrant(e)) continue;
        const int j = RedRegion((e + r) % kElements, (q + r) % kRedQuadrants);
        labels[j] = e == 0 ? kRed0 : kRed1;
        fixed[j] = true;
        const CellSample& c = fit.cells.red[(e + r) % kElements][(q + r) % kRedQuadrants];
        if (c.valid) (e == 0 ? zeros : ones).push_back(c.b);
      }
    }
    // Free cells start from the unconstrained fit, split at the middle of the orientation
    // cells' b* levels (the palette gives red and green the same two b* levels).
    const auto median = [](std::vector<double> v) {
      if (v.empty()) return 0.0;
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    const double mid = (median(ones) + median(zeros)) / 2;
    for (int e = 0; e < kElements; ++e) {
      for (int q = 0; q < kRedQuadrants; ++q) {
        const int j = RedRegion(e, q);
        if (!fixed[j]) labels[j] = fit.cells.red[e][q].b > mid ? kRed1 : kRed0;
      }
      for (int s = 0; s < kGreenSectors; ++s) {
        labels[GreenRegion(e, s)] = fit.cells.green[e][s].b > mid ? kGreen1 : kGreen0;
      }
    }
    Hypothesis& h = settled[r];
    model.settle(&labels, fixed, &h.colours);
    h.labels = labels;
    // Every residual that is compared comes from fitColours, so that equal labellings give
    // bit-identical residuals (a codeword equal to the free reading has excess exactly 0).
    ChannelResiduals residuals{};
    h.colours = model.fitColours(labels, &residuals);
    h.residual = Total(residuals);
  }
  return settled;
}

}  // namespace

SettledOrientations SettleOrientations(const BlurFit& fit) {
  if (!fit.ok || fit.equations.pixels == 0) return {};
  return Settle(ConstrainedModel(fit.equations), fit);
}

namespace {

// The orientation whose settled labelling explains the pixels best.
int BestSettled(const SettledOrientations& settled) {
  int best = 0;
  for (int r = 1; r < 4; ++r) {
    if (settled[r].residual < settled[best].residual) best = r;
  }
  return best;
}

// A residual as mean squared error per observed value (3 channels per pixel): the unit in which
// both readers' margins are stated.
double NoisePerValue(const BlurFit& fit, double residual) {
  return std::max(residual, 1e-12) / (3.0 * static_cast<double>(fit.equations.pixels));
}

}  // namespace

ModelReading ReadBitsThroughBlur(const BlurFit& fit, const SettledOrientations& settled,
                                 double min_significance) {
  ModelReading result;
  if (!fit.ok || fit.equations.pixels == 0) {
    result.error = "no blur fit";
    return result;
  }
  const ConstrainedModel model(fit.equations);
  const int best = BestSettled(settled);
  const double noise = NoisePerValue(fit, settled[best].residual);
  for (int r = 0; r < 4; ++r) {
    if (r != best && settled[r].residual - settled[best].residual < min_significance * noise) {
      result.error = "orientation ambiguous in the blur model";
      return result;
    }
  }

  // Now every cell is free, the orientation cells too: the format must hold on its own.
  Hypothesis h = settled[best];
  model.settle(&h.labels, std::array<bool, kRegions>{true, true}, &h.colours);
  const Colours& c = h.colours;
  // The colours found must look like the palette: two distinct b* levels per class.
  if (Bstar(c[kRed1]) - Bstar(c[kRed0]) < 20) {
    result.error = "blur model: red levels not apart in b*";
    return result;
  }
  std::array<int, kLevels> used{};
  for (int j = 0; j < kRegions; ++j) ++used[h.labels[j]];
  const bool greens_apart =
      used[kGreen0] > 0 && used[kGreen1] > 0 && Bstar(c[kGreen1]) - Bstar(c[kGreen0]) >= 20;

  const auto read = [&](int j, bool green, Bit* bit, double* margin) {
    const bool one = h.labels[j] == kRed1 || h.labels[j] == kGreen1;
    const double cost = model.flipCost(h.labels, c, j) / noise;
    *margin = (one ? 1 : -1) * std::min(1.0, cost / (4 * min_significance));
    if ((green && !greens_apart) || cost < min_significance) {
      *bit = Bit::kUnknown;
      ++result.unknown;
      return;
    }
    *bit = one ? Bit::kOne : Bit::kZero;
    result.min_known_margin = std::min(result.min_known_margin, std::abs(*margin));
  };
  for (int e = 0; e < kElements; ++e) {
    const int from = (e + best) % kElements;
    for (int s = 0; s < kGreenSectors; ++s) {
      read(GreenRegion(from, (s + 2 * best) % kGreenSectors), true, &result.reading.green[e][s],
           &result.margins.green[e][s]);
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      read(RedRegion(from, (q + best) % kRedQuadrants), false, &result.reading.red[e][q],
           &result.margins.red[e][q]);
    }
  }
  result.quarter_turns = best;
  result.ok = true;
  return result;
}

namespace {

// Canonical cell order for bit masks: green (e, s) at 8 e + s, red (e, q) at 32 + 4 e + q.
constexpr int kCanonicalCells = kElements * kCellsPerElement;
static_assert(kCanonicalCells <= 64);

int SampledRegion(int canonical, int quarter_turns) {
  const int r = quarter_turns;
  if (canonical < 32) {
    const int e = canonical / 8, s = canonical % 8;
    return GreenRegion((e + r) % kElements, (s + 2 * r) % kGreenSectors);
  }
  const int e = (canonical - 32) / 4, q = (canonical - 32) % 4;
  return RedRegion((e + r) % kElements, (q + r) % kRedQuadrants);
}

// Every key's 48 cells as a bit mask in canonical order, built once.
const std::vector<std::uint64_t>& Codebook() {
  static const std::vector<std::uint64_t> book = [] {
    std::vector<std::uint64_t> b(kKeyCount);
    for (int k = 0; k < kKeyCount; ++k) {
      const TagCells cells = EncodeCells(TagKey(static_cast<std::uint16_t>(k)));
      std::uint64_t mask = 0;
      for (int e = 0; e < kElements; ++e) {
        for (int g = 0; g < kGreenSectors; ++g) {
          if (cells.green[e][g]) mask |= std::uint64_t{1} << (8 * e + g);
        }
        for (int q = 0; q < kRedQuadrants; ++q) {
          if (cells.red[e][q]) mask |= std::uint64_t{1} << (32 + 4 * e + q);
        }
      }
      b[static_cast<std::size_t>(k)] = mask;
    }
    return b;
  }();
  return book;
}

bool IsOneLevel(int level) {
  return level == kRed1 || level == kGreen1;
}

}  // namespace

CodewordReading NearestCodewordThroughBlur(const BlurFit& fit, const SettledOrientations& settled,
                                           double min_margin, bool excuse_small_excess) {
  CodewordReading result;
  if (!fit.ok || fit.equations.pixels == 0) {
    result.error = "no blur fit";
    return result;
  }
  const ConstrainedModel model(fit.equations);
  // Residuals are compared in units of each channel's own noise, as the free reading leaves it
  // (brightness is sharper and less compressed than the colour differences, which JPEG keeps at
  // half resolution and quantises harder): each channel weighs 1 / its residual per pixel, so that
  // the free reading's weighted residual per value is 1, the unit of the lead and the excess.
  // Summed unweighted, the noisier colour differences decided more of the lead than they carry:
  // read at the true corners of the 864 tags of 24–48 px and tilts up to 72° of the seed 1–3
  // sweeps, the right codeword won with a lead of at least 75 and no excess on 614 tags instead of
  // 592, and on 581 instead of 558 with a lead of at least 150, where no wrong winner was left
  // (one before).
  ChannelResiduals free_channels{};
  model.fitColours(settled[BestSettled(settled)].labels, &free_channels);
  ChannelWeights weights{};
  for (int ch = 0; ch < 3; ++ch) {
    weights[ch] = static_cast<double>(fit.equations.pixels) / std::max(free_channels[ch], 1e-12);
  }
  double free_best = std::numeric_limits<double>::infinity();
  for (const SettledOrientation& orientation : settled) {
    ChannelResiduals residuals{};
    model.fitColours(orientation.labels, &residuals);
    free_best = std::min(free_best, Total(residuals, weights));
  }
  constexpr double kNoise = 1;  // weighted residual per value of the free reading

  // Rank every (key, orientation) by the summed cost of the cells where it disagrees with that
  // orientation's settled reading (each cell's flip cost, colours held): cheap, and close to
  // the exact residual when few cells differ.
  struct Candidate {
    double cost;
    int key;
    int turns;
  };
  // Best-ranked candidates whose exact residual is computed. On blurred small tags the ranking is
  // far from exact (flips of neighbouring cells interact): at the true corners of six seed-1 tags
  // (32 px, 55°, hard light) the right codeword explained the pixels better than the winner of
  // the 8 best-ranked on every one; it won among the best 64 on 3, among 512 on 4. Each exact
  // score is one 6 × 6 solve per channel.
  constexpr std::size_t kExact = 256;
  // Codewords differ in at least 4 of the 48 cells; 72 others lie within 6 of any codeword, 169
  // within 7.
  constexpr int kNeighbourCells = 7;
  constexpr int kNeighbourRounds = 4;
  std::vector<Candidate> ranked;
  const std::vector<std::uint64_t>& book = Codebook();
  for (int r = 0; r < 4; ++r) {
    const Hypothesis& h = settled[r];
    std::array<double, kCanonicalCells> cost{};
    std::uint64_t read = 0;
    for (int c = 0; c < kCanonicalCells; ++c) {
      const int j = SampledRegion(c, r);
      cost[c] = model.flipCost(h.labels, h.colours, j);
      if (IsOneLevel(h.labels[j])) read |= std::uint64_t{1} << c;
    }
    static_assert(kCanonicalCells % 8 == 0);
    // The summed cost of any set of differing cells, a byte of the mask at a time: six lookups
    // per key rather than a loop over its differing bits (the ranking was most of this call).
    std::array<std::array<double, 256>, kCanonicalCells / 8> by_byte{};
    for (std::size_t byte = 0; byte < by_byte.size(); ++byte) {
      by_byte[byte][0] = 0;
      for (unsigned v = 1; v < 256; ++v) {
        by_byte[byte][v] = by_byte[byte][v & (v - 1)] + cost[byte * 8 + std::countr_zero(v)];
      }
    }
    for (int k = 0; k < kKeyCount; ++k) {
      const std::uint64_t differ = book[static_cast<std::size_t>(k)] ^ read;
      double total = 0;
      for (std::size_t byte = 0; byte < by_byte.size(); ++byte) {
        total += by_byte[byte][(differ >> (8 * byte)) & 0xFFU];
      }
      if (ranked.size() < kExact || total < ranked.back().cost) {
        if (ranked.size() == kExact) ranked.pop_back();
        const Candidate candidate{total, k, r};
        ranked.insert(std::upper_bound(
                          ranked.begin(), ranked.end(), candidate,
                          [](const Candidate& x, const Candidate& y) { return x.cost < y.cost; }),
                      candidate);
      }
    }
  }

  // Exact residuals of those, colours refitted to each.
  struct Scored {
    double residual;
    Candidate candidate;
    Labels labels;
    Colours colours;
  };
  std::vector<Scored> scored;
  std::vector<bool> is_scored(4 * static_cast<std::size_t>(kKeyCount));
  const auto slot = [](int turns, int key) {
    return static_cast<std::size_t>(turns) * static_cast<std::size_t>(kKeyCount) +
           static_cast<std::size_t>(key);
  };
  const auto score = [&](const Candidate& c) {
    is_scored[slot(c.turns, c.key)] = true;
    Labels labels{};
    labels[0] = kQuietLevel, labels[1] = kBlackLevel;
    const std::uint64_t code = book[static_cast<std::size_t>(c.key)];
    for (int cell = 0; cell < kCanonicalCells; ++cell) {
      const bool one = ((code >> cell) & 1U) != 0;
      const bool green = cell < 32;
      labels[SampledRegion(cell, c.turns)] =
          green ? (one ? kGreen1 : kGreen0) : (one ? kRed1 : kRed0);
    }
    ChannelResiduals residuals{};
    const Colours colours = model.fitColours(labels, &residuals);
    scored.push_back({Total(residuals, weights), c, labels, colours});
  };
  for (const Candidate& c : ranked) score(c);
  const auto by_residual = [](const Scored& a, const Scored& b) { return a.residual < b.residual; };
  std::sort(scored.begin(), scored.end(), by_residual);
  // The ranking can leave out a codeword that explains the pixels better than the winner, and a
  // lead over the runner-up among those scored says nothing about it: at seed 9 (16 frames per
  // bin, frame 1543: 32 px at 55°, hard light) the winner led the scored runner-up by 182 noise
  // units and was read, while the true codeword, 5 cells away and never scored, explained the
  // pixels better by 65. Every codeword within kNeighbourCells cells of the winner (in its
  // orientation) is therefore scored too, and again around a new winner until it holds.
  for (int round = 0; round < kNeighbourRounds && !scored.empty(); ++round) {
    const Candidate winner = scored[0].candidate;
    const std::uint64_t winner_code = book[static_cast<std::size_t>(winner.key)];
    const std::size_t before = scored.size();
    for (int k = 0; k < kKeyCount; ++k) {
      if (is_scored[slot(winner.turns, k)] ||
          std::popcount(book[static_cast<std::size_t>(k)] ^ winner_code) > kNeighbourCells) {
        continue;
      }
      score({0, k, winner.turns});
    }
    if (scored.size() == before) break;
    std::sort(scored.begin(), scored.end(), by_residual);
    if (scored[0].candidate.key == winner.key && scored[0].candidate.turns == winner.turns) break;
  }
  if (scored.size() < 2) {
    result.error = "blur model: no codeword candidates";
    return result;
  }
  const Scored& best = scored[0];
  const double lead = (scored[1].residual - best.residual) / kNoise;
  const double excess = (best.residual - free_best) / kNoise;
  result.lead = lead;  // also when refused: they say by how much
  result.excess = excess;
  result.winner = TagKey(static_cast<std::uint16_t>(best.candidate.key));
  // The winner must beat every other codeword clearly and explain the pixels at least as well as
  // the free reading (the best labelling found without the code), or nearly as well when it leads
  // by far: by at most a tenth of a lead of at least 100. Its colours must look like the palette.
  // (Allowing any excess below the lead gave a misread at seed 5: 48 px, 55°, hard light, lead 299
  // and excess 78 noise units. Logged on seeds 1 and 2, refused winners that were the wrong key
  // had excess / lead from 0.26 to 3.4, or a lead below 100; most right ones had it below 0.1.)
  const bool excess_excused =
      excuse_small_excess && lead >= kMinLeadToExcuseExcess && excess <= kMaxExcessPerLead * lead;
  if (lead < min_margin || (excess > 0 && !excess_excused)) {
    result.error = "blur model: no codeword clearly nearest";
    return result;
  }
  // (Both red levels are in every codeword, through the orientation cells; the green ones only
  // when the payload has both bit values.)
  const std::uint64_t greens = book[static_cast<std::size_t>(best.candidate.key)] & 0xFFFFFFFFU;
  const bool both_greens = greens != 0 && greens != 0xFFFFFFFFU;
  if (Bstar(best.colours[kRed1]) - Bstar(best.colours[kRed0]) < 20 ||
      (both_greens && Bstar(best.colours[kGreen1]) - Bstar(best.colours[kGreen0]) < 20)) {
    result.error = "blur model: codeword colours unlike the palette";
    return result;
  }
  result.key = TagKey(static_cast<std::uint16_t>(best.candidate.key));
  result.quarter_turns = best.candidate.turns;
  const TagCells cells = EncodeCells(*result.key);
  for (int e = 0; e < kElements; ++e) {
    for (int g = 0; g < kGreenSectors; ++g) {
      result.reading.green[e][g] = cells.green[e][g] ? Bit::kOne : Bit::kZero;
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      result.reading.red[e][q] = cells.red[e][q] ? Bit::kOne : Bit::kZero;
    }
  }
  return result;
}

}  // namespace pintag::stage
