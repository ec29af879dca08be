#include "reading/palette_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "reading/region_fit.hpp"

namespace pintag::reading {

PaletteModel::PaletteModel(const LumaSystem& luma, const ChromaSystem& chroma,
                           std::array<double, 3> weights)
    : weights_(weights) {
  ata_[0] = luma.ata;
  ata_[1] = chroma.ata;
  for (std::size_t system = 0; system < 2; ++system) {
    std::vector<Entry>& entries = off_diagonal_[system];
    for (int j = 0; j < kModelRegions; ++j) {
      const auto row = static_cast<std::size_t>(j);
      row_start_[system][row] = static_cast<std::uint32_t>(entries.size());
      for (int k = 0; k < kModelRegions; ++k) {
        const double value = ata(static_cast<int>(system), j, k);
        if (k == j) {  // the diagonal is kept in ata_; what follows is right of it
          upper_start_[system][row] = static_cast<std::uint32_t>(entries.size());
        } else if (value != 0) {
          entries.push_back({static_cast<std::uint8_t>(k), value});
        }
      }
    }
    row_start_[system][kModelRegions] = static_cast<std::uint32_t>(entries.size());
  }
  aty_[0] = luma.aty[0];
  aty_[1] = chroma.aty[0];
  aty_[2] = chroma.aty[1];
  yty_ = {luma.yty[0], chroma.yty[0], chroma.yty[1]};
  const FreeFit<1> free_luma = SolveFree(luma);
  const FreeFit<2> free_chroma = SolveFree(chroma);
  for (int j = 0; j < kModelRegions; ++j) {
    const auto r = static_cast<std::size_t>(j);
    free_colour_[r] = {free_luma.colour[0][r], free_chroma.colour[0][r], free_chroma.colour[1][r]};
  }
}

namespace {

// Fixed-size arrays throughout: a codeword search fits several hundred labellings, and heap
// matrices cost more than the arithmetic at this size.
constexpr std::size_t kLevelCount = kLevels;
using Six = std::array<std::array<double, kLevelCount>, kLevelCount>;
using SixVector = std::array<double, kLevelCount>;

// Solves m z = rhs for the leading n × n block by Cholesky, in place (z holds rhs on entry).
// False, as OpenCV's solver, when a pivot falls below machine epsilon.
bool SolveCholesky(Six& m, SixVector& z, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j <= i; ++j) {
      double s = m[i][j];
      for (std::size_t k = 0; k < j; ++k) s -= m[i][k] * m[j][k];
      if (i == j) {
        if (s < std::numeric_limits<double>::epsilon()) return false;
        m[i][i] = std::sqrt(s);
      } else {
        m[i][j] = s / m[j][j];
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {  // L y = rhs
    for (std::size_t k = 0; k < i; ++k) z[i] -= m[i][k] * z[k];
    z[i] /= m[i][i];
  }
  for (std::size_t i = n; i-- > 0;) {  // Lᵀ z = y
    for (std::size_t k = i + 1; k < n; ++k) z[i] -= m[k][i] * z[k];
    z[i] /= m[i][i];
  }
  return true;
}

// One channel's least-squares colours over the six levels, with `ties`: level `one` held at level
// `zero` plus `step` (x = T z + c for the free levels z; a tie's zero is never itself tied).
// Returns the residual yᵀy − 2 xᵀb + xᵀBx.
struct Tie {
  int zero, one;
  double step;
};
double SolveChannel(const Six& b, const SixVector& bty, double yty, std::span<const Tie> ties,
                    SixVector* x) {
  // Which unknown each level's colour is: its own, or (tied) its zero's.
  std::array<std::size_t, kLevelCount> unknown{};
  std::array<bool, kLevelCount> tied{};
  SixVector c{};
  for (const Tie& tie : ties) {
    tied[static_cast<std::size_t>(tie.one)] = true;
    c[static_cast<std::size_t>(tie.one)] = tie.step;
  }
  std::size_t free = 0;
  for (std::size_t l = 0; l < kLevelCount; ++l) {
    if (!tied[l]) unknown[l] = free++;
  }
  for (const Tie& tie : ties) {
    unknown[static_cast<std::size_t>(tie.one)] = unknown[static_cast<std::size_t>(tie.zero)];
  }
  // Tᵀ B T and Tᵀ (b − B c): T adds each tied level's row and column to its zero's.
  Six reduced{};
  SixVector z{};
  for (std::size_t l = 0; l < kLevelCount; ++l) {
    double bc = 0;
    for (std::size_t m = 0; m < kLevelCount; ++m) {
      reduced[unknown[l]][unknown[m]] += b[l][m];
      bc += b[l][m] * c[m];
    }
    z[unknown[l]] += bty[l] - bc;
  }
  double trace = 0;
  for (std::size_t i = 0; i < free; ++i) trace += reduced[i][i];
  for (std::size_t i = 0; i < free; ++i) reduced[i][i] += 1e-9 * trace + 1e-12;  // unused levels
  if (!SolveCholesky(reduced, z, free)) z.fill(0);
  for (std::size_t l = 0; l < kLevelCount; ++l) (*x)[l] = z[unknown[l]] + c[l];
  double quadratic = 0;
  for (std::size_t l = 0; l < kLevelCount; ++l) {
    double bx = 0;
    for (std::size_t m = 0; m < kLevelCount; ++m) bx += b[l][m] * (*x)[m];
    quadratic += (*x)[l] * (bx - 2 * bty[l]);
  }
  return yty + quadratic;
}

}  // namespace

LevelSystem PaletteModel::levelSystem(const Labels& labels) const {
  LevelSystem level_system;
  for (std::size_t j = 0; j < kModelRegions; ++j) {
    ++level_system.regions[static_cast<std::size_t>(labels[j])];
  }
  // B[l][m] sums AᵀA[j][k] over the regions j at level l and k at level m. AᵀA is symmetric, so
  // each pair j < k is taken once: the part of row j right of the diagonal is summed by its
  // regions' levels into row labels[j] of `upper`, and B is `upper` plus its transpose and the
  // diagonal's sums (BM_Stage5c_DecideCodeword 10.0 -> 8.4 ms). The row is summed in registers
  // first, against a one-hot of the level (multiplying by 0 or 1 is exact): adding straight into
  // B made each entry wait for the store of the one before (7.9 -> 7.3 ms).
  static constexpr Six kOneHot = [] {
    Six m{};
    for (std::size_t l = 0; l < kLevelCount; ++l) m[l][l] = 1;
    return m;
  }();
  for (std::size_t system = 0; system < 2; ++system) {
    Six& b = level_system.btb[system];
    Six upper{};  // the pairs j < k, by (level of j, level of k)
    SixVector diagonal{};
    const std::vector<Entry>& entries = off_diagonal_[system];
    const auto& starts = row_start_[system];
    for (std::size_t j = 0; j < kModelRegions; ++j) {
      SixVector sum{};
      for (std::uint32_t e = upper_start_[system][j]; e < starts[j + 1]; ++e) {
        const SixVector& level = kOneHot[static_cast<std::size_t>(labels[entries[e].k])];
        for (std::size_t m = 0; m < kLevelCount; ++m) sum[m] += entries[e].value * level[m];
      }
      SixVector& row = upper[static_cast<std::size_t>(labels[j])];
      for (std::size_t m = 0; m < kLevelCount; ++m) row[m] += sum[m];
      diagonal[static_cast<std::size_t>(labels[j])] +=
          ata(static_cast<int>(system), static_cast<int>(j), static_cast<int>(j));
    }
    for (std::size_t l = 0; l < kLevelCount; ++l) {
      for (std::size_t m = 0; m < kLevelCount; ++m) b[l][m] = upper[l][m] + upper[m][l];
      b[l][l] += diagonal[l];
    }
  }
  for (std::size_t ch = 0; ch < 3; ++ch) {
    for (std::size_t j = 0; j < kModelRegions; ++j) {
      level_system.bty[ch][static_cast<std::size_t>(labels[j])] += aty_[ch][j];
    }
  }
  return level_system;
}

LevelSystem PaletteModel::relabelled(LevelSystem system, const Labels& from,
                                     const Labels& to) const {
  Labels now = from;
  for (std::size_t j = 0; j < kModelRegions; ++j) {
    const auto old_level = static_cast<std::size_t>(now[j]);
    const auto new_level = static_cast<std::size_t>(to[j]);
    if (old_level == new_level) continue;
    // Region j leaves row and column old_level of B for new_level's, against every other
    // region's level as it stands (regions moved before j at their new level).
    for (std::size_t s = 0; s < 2; ++s) {
      Six& b = system.btb[s];
      for (std::uint32_t e = row_start_[s][j]; e < row_start_[s][j + 1]; ++e) {
        const Entry& entry = off_diagonal_[s][e];
        const auto other = static_cast<std::size_t>(now[entry.k]);
        b[old_level][other] -= entry.value;
        b[other][old_level] -= entry.value;
        b[new_level][other] += entry.value;
        b[other][new_level] += entry.value;
      }
      const double self = ata(static_cast<int>(s), static_cast<int>(j), static_cast<int>(j));
      b[old_level][old_level] -= self;
      b[new_level][new_level] += self;
    }
    for (std::size_t ch = 0; ch < 3; ++ch) {
      system.bty[ch][old_level] -= aty_[ch][j];
      system.bty[ch][new_level] += aty_[ch][j];
    }
    --system.regions[old_level];
    ++system.regions[new_level];
    now[j] = to[j];
  }
  // A level no region holds any more is zero, not what rounding left of it: the solve's
  // regularisation then gives it the colour levelSystem's zeros would.
  for (std::size_t l = 0; l < kLevelCount; ++l) {
    if (system.regions[l] != 0) continue;
    for (std::size_t s = 0; s < 2; ++s) {
      for (std::size_t m = 0; m < kLevelCount; ++m) system.btb[s][l][m] = system.btb[s][m][l] = 0;
    }
    for (std::size_t ch = 0; ch < 3; ++ch) system.bty[ch][l] = 0;
  }
  return system;
}

PaletteColours PaletteModel::fit(const LevelSystem& system, double* residual,
                                 ChannelResiduals* by_channel) const {
  PaletteColours colours{};
  const auto used = [&](int level) { return system.regions[static_cast<std::size_t>(level)] > 0; };
  // The palette's order, where the free fit breaks it (kMinLumaStep, kMinCbStep): a class's one
  // is held that much brighter (luminance) or yellower (lower Cb) than its zero, so that a
  // codeword asking for a colour the tag does not have pays for it in its residual instead of
  // fitting noise with a free extra colour.
  double total = 0;
  double range = 0;
  for (int ch = 0; ch < 3; ++ch) {
    const Six& b = system.btb[static_cast<std::size_t>(SystemOf(ch))];
    const SixVector& bty = system.bty[static_cast<std::size_t>(ch)];
    const double yty = yty_[static_cast<std::size_t>(ch)];
    SixVector x{};
    double rss = SolveChannel(b, bty, yty, {}, &x);
    if (ch == 0) range = std::max(0.0, x[kQuietLevel] - x[kBlackLevel]);
    if (ch < 2) {
      // Red has both levels in every codeword (the orientation cells); its step, as this photo
      // shows it (cast, exposure, saturation), sets the least step of green: the palette gives
      // green a larger luminance step than red (0.19 against 0.13) and the same step in Cb.
      const double least = ch == 0 ? kMinLumaStep * range : kMinCbStep;
      const auto step = [&](int zero, int one) {
        return ch == 0 ? x[static_cast<std::size_t>(one)] - x[static_cast<std::size_t>(zero)]
                       : x[static_cast<std::size_t>(zero)] - x[static_cast<std::size_t>(one)];
      };
      std::array<Tie, 2> ties{};
      std::size_t tie_count = 0;
      const double sign = ch == 0 ? 1 : -1;
      double red_step = step(kRed0, kRed1);
      if (red_step < least) {
        ties[tie_count++] = {kRed0, kRed1, sign * least};
        red_step = least;
      }
      const double green_least =
          std::max(least, (ch == 0 ? kGreenLumaStepOfRed : kGreenCbStepOfRed) * red_step);
      if (used(kGreen0) && used(kGreen1) && step(kGreen0, kGreen1) < green_least) {
        ties[tie_count++] = {kGreen0, kGreen1, sign * green_least};
      }
      if (tie_count > 0) rss = SolveChannel(b, bty, yty, std::span(ties.data(), tie_count), &x);
    }
    for (int l = 0; l < kLevels; ++l) {
      colours[static_cast<std::size_t>(l)][static_cast<std::size_t>(ch)] =
          x[static_cast<std::size_t>(l)];
    }
    const double weighted = weights_[static_cast<std::size_t>(ch)] * std::max(0.0, rss);
    if (by_channel != nullptr) (*by_channel)[static_cast<std::size_t>(ch)] = weighted;
    total += weighted;
  }
  if (residual != nullptr) *residual = total;
  return colours;
}

double PaletteModel::flipCost(const Labels& labels, const PaletteColours& colours, int j) const {
  const auto& now = colours[static_cast<std::size_t>(labels[static_cast<std::size_t>(j)])];
  const auto& other =
      colours[static_cast<std::size_t>(Flipped(labels[static_cast<std::size_t>(j)]))];
  double cost = 0;
  for (int ch = 0; ch < 3; ++ch) {
    const auto c = static_cast<std::size_t>(ch);
    const int system = SystemOf(ch);
    const double d = other[c] - now[c];
    double g = 0;
    for (int k = 0; k < kModelRegions; ++k) {
      g += ata(system, j, k) *
           colours[static_cast<std::size_t>(labels[static_cast<std::size_t>(k)])][c];
    }
    cost += weights_[c] * d *
            (2 * g - 2 * aty_[c][static_cast<std::size_t>(j)] + d * ata(system, j, j));
  }
  return cost;
}

void PaletteModel::settle(Labels* labels, const std::array<bool, kModelRegions>& fixed,
                          PaletteColours* colours) const {
  *colours = fit(*labels);
  for (int round = 0; round < 8; ++round) {
    bool changed = false;
    for (int sweep = 0; sweep < 8; ++sweep) {
      bool flipped = false;
      for (int j = 2; j < kModelRegions; ++j) {
        if (fixed[static_cast<std::size_t>(j)] || flipCost(*labels, *colours, j) >= 0) continue;
        (*labels)[static_cast<std::size_t>(j)] = Flipped((*labels)[static_cast<std::size_t>(j)]);
        flipped = changed = true;
      }
      if (!flipped) break;
    }
    if (!changed) break;
    *colours = fit(*labels);
  }
}

}  // namespace pintag::reading
