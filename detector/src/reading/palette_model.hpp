#pragma once
// The printed tag's own model: six colours (quiet zone, black, red 0 and 1, green 0 and 1), each
// region taking one of its class's two. Given a labelling of the 50 regions, the colours follow
// by least squares from the free model's normal equations, without touching the pixels again; so
// does the residual, channel by channel, weighted by each channel's noise.

#include <array>
#include <cstdint>
#include <vector>

#include "reading/region_system.hpp"

namespace pintag::reading {

using Labels = std::array<int, kModelRegions>;

/// The palette's order (DESIGN.md's colours): a class's one is brighter and yellower (lower Cb)
/// than its zero; green 1 by 0.19 of the black-to-white luminance step and 0.36 in Cb, red 1 by
/// 0.13 and 0.35. Casts, exposure and blur shrink the steps; about three fifths of the smaller
/// luminance one and a third of the Cb one are held as least steps. The least steps were a third
/// and a sixth until the reader probe (tuning seeds 22-24, 24 frames per bin, corners jittered by
/// 0.6 px, 2 draws: 10,080 readings): a runner-up that differs from the truth in a few cells
/// could fit them with a level barely apart from its class's other; the larger steps lengthen
/// right winners' leads on the target readings (median +18-20 % in moderate light, +6-10 % in
/// hard; wrong winners' +4 %), and the same decision rule accepts 24 more moderate-light and 22
/// more hard-light target readings, none wrong (docs/DETECTOR-RESEARCH.md, twelfth sitting).
inline constexpr double kMinLumaStep = 0.08;  ///< of the quiet zone's luminance over the black's
inline constexpr double kMinCbStep = 0.12;
/// Green's least steps as parts of red's (the palette's: 1.46 in luminance, 1.0 in Cb).
inline constexpr double kGreenLumaStepOfRed = 0.75;
inline constexpr double kGreenCbStepOfRed = 0.5;
/// Per level, Y′, Cb, Cr.
using PaletteColours = std::array<std::array<double, 3>, kLevels>;
/// A weighted residual's parts: Y′, Cb, Cr.
using ChannelResiduals = std::array<double, 3>;

/// A labelling's equations over the six levels: B = Σ AᵀA[j][k] by the levels of j and k (one per
/// system: luma, chroma) and Bᵀy = Σ Aᵀy[j] by the level of j (one per channel), and how many
/// regions each level holds. What PaletteModel::fit solves.
struct LevelSystem {
  std::array<std::array<std::array<double, kLevels>, kLevels>, 2> btb{};
  std::array<std::array<double, kLevels>, 3> bty{};
  std::array<int, kLevels> regions{};
};

class PaletteModel {
 public:
  /// `weights`: each channel's (Y′, Cb, Cr) residual is multiplied by its weight (1 / its noise
  /// variance), so that residuals are in noise units.
  PaletteModel(const LumaSystem& luma, const ChromaSystem& chroma, std::array<double, 3> weights);

  /// The colours that explain the samples best under `labels`, each class's one held at least the
  /// least steps above its zero, and with `residual` the weighted residual they leave (yᵀy − 2 xᵀb
  /// + xᵀBx per channel, from the labels' 6 × 6 equations); `by_channel`, that residual's parts
  /// (Y′, Cb, Cr).
  PaletteColours fit(const Labels& labels, double* residual = nullptr,
                     ChannelResiduals* by_channel = nullptr) const {
    return fit(levelSystem(labels), residual, by_channel);
  }
  PaletteColours fit(const LevelSystem& system, double* residual = nullptr,
                     ChannelResiduals* by_channel = nullptr) const;

  /// The labels' level system, summed over every region.
  LevelSystem levelSystem(const Labels& labels) const;

  /// The level system of `to`, from `system` (that of `from`) by moving the regions whose level
  /// differs between the two: a codeword search scores hundreds of codewords a few cells from one
  /// it has scored, and summing only those cells' rows costs a fraction of summing all 50. The
  /// sums differ from levelSystem(to)'s only by rounding; a level left empty is exactly zero.
  LevelSystem relabelled(LevelSystem system, const Labels& from, const Labels& to) const;

  /// Change of the weighted residual if region `j` took the other level of its class, colours held.
  double flipCost(const Labels& labels, const PaletteColours& colours, int j) const;

  /// Iterated conditional modes: flips every free region that lowers the residual, refits the
  /// colours, until nothing changes (or a few rounds).
  void settle(Labels* labels, const std::array<bool, kModelRegions>& fixed,
              PaletteColours* colours) const;

  /// The free fit's colour of region `j` (Y′, Cb, Cr), for starting labellings.
  const std::array<double, 3>& freeColour(int j) const {
    return free_colour_[static_cast<std::size_t>(j)];
  }

 private:
  double ata(int system, int j, int k) const {
    return ata_[static_cast<std::size_t>(system)]
               [(static_cast<std::size_t>(j) * kModelRegions) + static_cast<std::size_t>(k)];
  }
  // Channel c's system: Y′ is the luma one, Cb and Cr share the chroma one.
  static int SystemOf(int channel) { return channel == 0 ? 0 : 1; }

  // AᵀA's non-zero entries off the diagonal, row by row, each row's in column order: a blur of a
  // pixel or two reaches few regions, so most of AᵀA is zero. Row j's entries are
  // off_diagonal_[system][row_start_[system][j] … row_start_[system][j + 1]); those right of the
  // diagonal begin at upper_start_[system][j]. With the diagonal, the labels' 6 × 6 sums take only
  // the entries right of it (AᵀA is symmetric); relabelled takes whole rows.
  struct Entry {
    std::uint8_t k;
    double value;
  };
  std::array<std::vector<Entry>, 2> off_diagonal_;
  std::array<std::array<std::uint32_t, kModelRegions + 1>, 2> row_start_{};
  std::array<std::array<std::uint32_t, kModelRegions>, 2> upper_start_{};
  std::array<std::array<double, std::size_t{kModelRegions} * kModelRegions>, 2> ata_{};
  std::array<std::array<double, kModelRegions>, 3> aty_{};
  std::array<double, 3> yty_{};
  std::array<double, 3> weights_{};
  std::array<std::array<double, 3>, kModelRegions> free_colour_{};
};

}  // namespace pintag::reading
