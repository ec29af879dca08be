// The palette model (reading/palette_model.hpp) solves each labelling from the normal equations
// alone. These tests build a least-squares problem whose samples they keep, and check its colours,
// residuals and flip costs against a plain solve over those samples.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>
#include <string>

#include "reading/palette_model.hpp"

namespace pintag::reading {
namespace {

// Samples of one system: each a blur-like mix of a few regions (weights summing to one), and its
// values per channel.
struct Samples {
  std::vector<std::array<double, kModelRegions>> mix;
  std::vector<std::vector<double>> value;  // [channel][sample]
};

// The palette's six colours, Y′ Cb Cr, on a 0 … 1 scale (a one brighter and lower in Cb).
using Colours = std::array<std::array<double, 3>, kLevels>;

Samples MakeSamples(const Labels& labels, const Colours& truth, int channels, int channel0,
                    int count, double noise, std::mt19937& rng) {
  Samples s;
  s.value.resize(static_cast<std::size_t>(channels));
  std::uniform_int_distribution<int> region(0, kModelRegions - 1);
  std::uniform_int_distribution<int> spread(1, 4);
  std::uniform_real_distribution<double> share(0.1, 1.0);
  std::normal_distribution<double> error(0, noise);
  for (int i = 0; i < count; ++i) {
    std::array<double, kModelRegions> mix{};
    // Every region is seen by some sample; the rest land anywhere.
    const int centre = i < kModelRegions ? i : region(rng);
    mix[static_cast<std::size_t>(centre)] += 1.0;
    for (int n = spread(rng) - 1; n > 0; --n)
      mix[static_cast<std::size_t>(region(rng))] += share(rng);
    double total = 0;
    for (const double m : mix) total += m;
    for (double& m : mix) m /= total;
    for (int ch = 0; ch < channels; ++ch) {
      double v = 0;
      for (int j = 0; j < kModelRegions; ++j) {
        v += mix[static_cast<std::size_t>(j)] *
             truth[static_cast<std::size_t>(labels[static_cast<std::size_t>(j)])]
                  [static_cast<std::size_t>(channel0) + static_cast<std::size_t>(ch)];
      }
      s.value[static_cast<std::size_t>(ch)].push_back(v + error(rng));
    }
    s.mix.push_back(mix);
  }
  return s;
}

template <int kChannels>
RegionSystem<kChannels> NormalEquations(const Samples& s) {
  RegionSystem<kChannels> system;
  for (std::size_t i = 0; i < s.mix.size(); ++i) {
    for (int j = 0; j < kModelRegions; ++j) {
      for (int k = 0; k < kModelRegions; ++k) {
        system.ata[(static_cast<std::size_t>(j) * kModelRegions) + static_cast<std::size_t>(k)] +=
            s.mix[i][static_cast<std::size_t>(j)] * s.mix[i][static_cast<std::size_t>(k)];
      }
      for (int ch = 0; ch < kChannels; ++ch) {
        system.aty[static_cast<std::size_t>(ch)][static_cast<std::size_t>(j)] +=
            s.mix[i][static_cast<std::size_t>(j)] * s.value[static_cast<std::size_t>(ch)][i];
      }
    }
    for (int ch = 0; ch < kChannels; ++ch) {
      const double v = s.value[static_cast<std::size_t>(ch)][i];
      system.yty[static_cast<std::size_t>(ch)] += v * v;
    }
    ++system.samples;
    system.weight += 1;
  }
  return system;
}

// Σ over samples of (value − the sample's mix of `colours` under `labels`)², one channel.
double SquaredError(const Samples& s, int ch, const Labels& labels, const PaletteColours& colours,
                    int colour_channel) {
  double sum = 0;
  for (std::size_t i = 0; i < s.mix.size(); ++i) {
    double predicted = 0;
    for (int j = 0; j < kModelRegions; ++j) {
      predicted += s.mix[i][static_cast<std::size_t>(j)] *
                   colours[static_cast<std::size_t>(labels[static_cast<std::size_t>(j)])]
                          [static_cast<std::size_t>(colour_channel)];
    }
    const double e = s.value[static_cast<std::size_t>(ch)][i] - predicted;
    sum += e * e;
  }
  return sum;
}

// Least squares over the samples for one channel, with level `tied_one` (if ≥ 0) held at level
// `tied_one − 1` (its class's zero) plus `step`: the six colours.
std::array<double, kLevels> PlainSolve(const Samples& s, int ch, const Labels& labels,
                                       int tied_one = -1, double step = 0) {
  const int unknowns = tied_one >= 0 ? kLevels - 1 : kLevels;
  const auto column = [&](int level) {
    if (tied_one < 0) return level;
    const int l = level == tied_one ? level - 1 : level;
    return l > tied_one ? l - 1 : l;
  };
  cv::Mat design(static_cast<int>(s.mix.size()), unknowns, CV_64F, cv::Scalar(0));
  cv::Mat rhs(static_cast<int>(s.mix.size()), 1, CV_64F);
  for (std::size_t i = 0; i < s.mix.size(); ++i) {
    double fixed = 0;
    for (int j = 0; j < kModelRegions; ++j) {
      const int level = labels[static_cast<std::size_t>(j)];
      const double m = s.mix[i][static_cast<std::size_t>(j)];
      design.at<double>(static_cast<int>(i), column(level)) += m;
      if (level == tied_one) fixed += m * step;
    }
    rhs.at<double>(static_cast<int>(i)) = s.value[static_cast<std::size_t>(ch)][i] - fixed;
  }
  cv::Mat z;
  cv::solve(design, rhs, z, cv::DECOMP_SVD);
  std::array<double, kLevels> x{};
  for (int l = 0; l < kLevels; ++l) {
    x[static_cast<std::size_t>(l)] = z.at<double>(column(l)) + (l == tied_one ? step : 0);
  }
  return x;
}

Labels RandomLabels(std::mt19937& rng) {
  Labels labels{};
  labels[kQuietRegion] = kQuietLevel;
  labels[kBlackRegion] = kBlackLevel;
  std::bernoulli_distribution one(0.5);
  for (int j = 2; j < kModelRegions; ++j) {
    const bool green = (j - 2) % kCellsPerElement >= kRedQuadrants;
    labels[static_cast<std::size_t>(j)] =
        green ? (one(rng) ? kGreen1 : kGreen0) : (one(rng) ? kRed1 : kRed0);
  }
  // Both levels of each class appear (as in every codeword).
  labels[2] = kRed0, labels[3] = kRed1, labels[6] = kGreen0, labels[7] = kGreen1;
  return labels;
}

// A printed palette as a phone sees it: quiet 0.9, black 0.1; ones brighter and lower in Cb.
Colours PrintedPalette() {
  Colours c{};
  c[kQuietLevel] = {0.90, 0.50, 0.50};
  c[kBlackLevel] = {0.10, 0.50, 0.50};
  c[kRed0] = {0.35, 0.55, 0.75};
  c[kRed1] = {0.48, 0.30, 0.70};
  c[kGreen0] = {0.45, 0.55, 0.35};
  c[kGreen1] = {0.64, 0.30, 0.40};
  return c;
}

struct Problem {
  Samples luma, chroma;
  std::array<double, 3> weights{};
  PaletteModel model;
};

Problem MakeProblem(const Labels& truth_labels, const Colours& palette, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Samples luma = MakeSamples(truth_labels, palette, 1, 0, 900, 0.02, rng);
  Samples chroma = MakeSamples(truth_labels, palette, 2, 1, 300, 0.03, rng);
  const std::array<double, 3> weights{1 / (0.02 * 0.02), 1 / (0.03 * 0.03), 1 / (0.03 * 0.03)};
  PaletteModel model(NormalEquations<1>(luma), NormalEquations<2>(chroma), weights);
  return {std::move(luma), std::move(chroma), weights, model};
}

double WeightedResidual(const Problem& p, const Labels& labels, const PaletteColours& colours) {
  return p.weights[0] * SquaredError(p.luma, 0, labels, colours, 0) +
         p.weights[1] * SquaredError(p.chroma, 0, labels, colours, 1) +
         p.weights[2] * SquaredError(p.chroma, 1, labels, colours, 2);
}

TEST(PaletteModel, FitsTheColoursAPlainSolveOverTheSamplesFinds) {
  std::mt19937 rng(7);
  const Colours palette = PrintedPalette();
  int compared = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const Labels truth = RandomLabels(rng);
    const Problem p = MakeProblem(truth, palette, 100 + static_cast<std::uint32_t>(trial));
    // The true labelling and wrong ones: the palette's order holds in every channel's free fit
    // here, so no step is held and each channel is an unconstrained solve.
    for (const Labels& labels : {truth, RandomLabels(rng)}) {
      double residual = 0;
      const PaletteColours colours = p.model.fit(labels, &residual);
      const std::array<std::array<double, kLevels>, 3> plain = {PlainSolve(p.luma, 0, labels),
                                                                PlainSolve(p.chroma, 0, labels),
                                                                PlainSolve(p.chroma, 1, labels)};
      // The model holds a one at its zero plus a least step when the free solve's step is
      // smaller (palette_model.hpp); compare only where every step clears that rule with room.
      bool ordered = true;
      for (int ch = 0; ch < 2; ++ch) {
        const auto& x = plain[static_cast<std::size_t>(ch)];
        const double sign = ch == 0 ? 1 : -1;
        const double least =
            ch == 0 ? kMinLumaStep * (plain[0][kQuietLevel] - plain[0][kBlackLevel]) : kMinCbStep;
        const double red_step = sign * (x[kRed1] - x[kRed0]);
        const double green_least =
            std::max(least, (ch == 0 ? kGreenLumaStepOfRed : kGreenCbStepOfRed) * red_step);
        ordered = ordered && red_step > least + 0.01 &&
                  sign * (x[kGreen1] - x[kGreen0]) > green_least + 0.01;
      }
      if (!ordered) continue;  // a wrong labelling may break the order; the next test covers it
      ++compared;
      for (int l = 0; l < kLevels; ++l) {
        for (int ch = 0; ch < 3; ++ch) {
          EXPECT_NEAR(colours[static_cast<std::size_t>(l)][static_cast<std::size_t>(ch)],
                      plain[static_cast<std::size_t>(ch)][static_cast<std::size_t>(l)], 1e-6)
              << "trial " << trial << " level " << l << " channel " << ch;
        }
      }
      EXPECT_NEAR(residual, WeightedResidual(p, labels, colours), 1e-6 * residual);
    }
  }
  EXPECT_GE(compared, 8);  // at least every true labelling
}

TEST(PaletteModel, HoldsAOneThatComesOutDarkerThanItsZeroAtTheLeastStep) {
  // A photo whose red ones are no brighter than its red zeros (a labelling that swaps them, or a
  // cast): the fit must not explain it with a reversed palette, but hold red 1 at red 0 plus the
  // least step, and then be the best colours under that constraint.
  Colours palette = PrintedPalette();
  palette[kRed1][0] = palette[kRed0][0] - 0.05;
  std::mt19937 rng(11);
  const Labels labels = RandomLabels(rng);
  const Problem p = MakeProblem(labels, palette, 12);
  double residual = 0;
  const PaletteColours colours = p.model.fit(labels, &residual);
  // The least step is a part of the black-to-quiet range the unconstrained fit sees.
  const std::array<double, kLevels> free = PlainSolve(p.luma, 0, labels);
  const double least = kMinLumaStep * (free[kQuietLevel] - free[kBlackLevel]);
  ASSERT_LT(free[kRed1] - free[kRed0], least);
  EXPECT_NEAR(colours[kRed1][0] - colours[kRed0][0], least, 1e-6);
  const std::array<double, kLevels> plain = PlainSolve(p.luma, 0, labels, kRed1, least);
  for (int l = 0; l < kLevels; ++l) {
    EXPECT_NEAR(colours[static_cast<std::size_t>(l)][0], plain[static_cast<std::size_t>(l)], 1e-6)
        << "level " << l;
  }
  EXPECT_NEAR(residual, WeightedResidual(p, labels, colours), 1e-6 * residual);
}

TEST(PaletteModel, FlipCostIsTheResidualChangeOfOneRegionTakingItsOtherLevel) {
  std::mt19937 rng(5);
  const Labels labels = RandomLabels(rng);
  const Problem p = MakeProblem(labels, PrintedPalette(), 6);
  const PaletteColours colours = p.model.fit(labels);
  const double before = WeightedResidual(p, labels, colours);
  for (int j = 2; j < kModelRegions; ++j) {
    Labels flipped = labels;
    flipped[static_cast<std::size_t>(j)] = Flipped(labels[static_cast<std::size_t>(j)]);
    const double change = WeightedResidual(p, flipped, colours) - before;
    EXPECT_NEAR(p.model.flipCost(labels, colours, j), change, 1e-6 * before) << "region " << j;
    // The true labelling explains the samples best: every single flip costs.
    EXPECT_GT(change, 0) << "region " << j;
  }
}

TEST(PaletteModel, RelabelledGivesTheSumsAndFitOfTheLabellingItMovesTo) {
  std::mt19937 rng(9);
  const Labels truth = RandomLabels(rng);
  const Problem p = MakeProblem(truth, PrintedPalette(), 10);
  const LevelSystem from_truth = p.model.levelSystem(truth);
  const auto expect_same = [&](const Labels& to, const std::string& what) {
    const LevelSystem direct = p.model.levelSystem(to);
    const LevelSystem moved = p.model.relabelled(from_truth, truth, to);
    EXPECT_EQ(moved.regions, direct.regions) << what;
    for (std::size_t s = 0; s < 2; ++s) {
      for (std::size_t l = 0; l < kLevels; ++l) {
        for (std::size_t m = 0; m < kLevels; ++m) {
          EXPECT_NEAR(moved.btb[s][l][m], direct.btb[s][l][m], 1e-9 * (1 + direct.btb[s][l][l]))
              << what << " system " << s << " B[" << l << "][" << m << "]";
          // An empty level is zero exactly, as levelSystem leaves it.
          if (direct.regions[l] == 0) {
            EXPECT_EQ(moved.btb[s][l][m], 0) << what;
          }
        }
      }
    }
    for (std::size_t ch = 0; ch < 3; ++ch) {
      for (std::size_t l = 0; l < kLevels; ++l) {
        EXPECT_NEAR(moved.bty[ch][l], direct.bty[ch][l], 1e-9 * (1 + std::abs(direct.bty[ch][l])))
            << what;
        if (direct.regions[l] == 0) {
          EXPECT_EQ(moved.bty[ch][l], 0) << what;
        }
      }
    }
    double direct_residual = 0, moved_residual = 0;
    const PaletteColours direct_colours = p.model.fit(direct, &direct_residual);
    const PaletteColours moved_colours = p.model.fit(moved, &moved_residual);
    EXPECT_NEAR(moved_residual, direct_residual, 1e-9 * direct_residual) << what;
    for (std::size_t l = 0; l < kLevels; ++l) {
      for (std::size_t ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(moved_colours[l][ch], direct_colours[l][ch], 1e-9) << what;
      }
    }
  };
  // A few cells off, as a codeword's neighbours are; many cells off; every green a zero (key 0's
  // greens: green 1 left empty); and the labelling itself.
  for (int trial = 0; trial < 20; ++trial) {
    Labels to = truth;
    std::uniform_int_distribution<int> region(2, kModelRegions - 1);
    const int flips = trial < 10 ? 1 + trial % 7 : 20 + trial;
    for (int f = 0; f < flips; ++f) {
      const auto j = static_cast<std::size_t>(region(rng));
      to[j] = Flipped(to[j]);
    }
    expect_same(to, "trial " + std::to_string(trial));
  }
  Labels greens_zero = truth;
  for (int& level : greens_zero) level = level == kGreen1 ? kGreen0 : level;
  expect_same(greens_zero, "every green a zero");
  expect_same(truth, "no change");
}

}  // namespace
}  // namespace pintag::reading
