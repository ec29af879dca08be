#include "reading/palette_model.hpp"

#include <algorithm>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "reading/region_fit.hpp"

namespace pintag::reading {

PaletteModel::PaletteModel(const LumaSystem& luma, const ChromaSystem& chroma,
                           std::array<double, 3> weights)
    : weights_(weights) {
  ata_[0] = luma.ata;
  ata_[1] = chroma.ata;
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

using Six = cv::Matx<double, kLevels, kLevels>;
using SixVector = cv::Matx<double, kLevels, 1>;

// One channel's least-squares colours over the six levels, with `ties`: level `one` held at level
// `zero` plus `step` (x = T z + c for the free levels z). Returns the residual yᵀy − 2 xᵀb + xᵀBx.
struct Tie {
  int zero, one;
  double step;
};
double SolveChannel(const Six& b, const SixVector& bty, double yty, const std::vector<Tie>& ties,
                    SixVector* x) {
  std::array<int, kLevels> free_index{};
  int free = 0;
  for (int l = 0; l < kLevels; ++l) {
    const bool tied =
        std::any_of(ties.begin(), ties.end(), [&](const Tie& t) { return t.one == l; });
    free_index[static_cast<std::size_t>(l)] = tied ? -1 : free++;
  }
  cv::Mat t = cv::Mat::zeros(kLevels, free, CV_64F);
  SixVector c = SixVector::zeros();
  for (int l = 0; l < kLevels; ++l) {
    if (free_index[static_cast<std::size_t>(l)] >= 0)
      t.at<double>(l, free_index[static_cast<std::size_t>(l)]) = 1;
  }
  for (const Tie& tie : ties) {
    t.at<double>(tie.one, free_index[static_cast<std::size_t>(tie.zero)]) = 1;
    c(tie.one) = tie.step;
  }
  const cv::Mat bm(b), btym(bty), cm(c);
  cv::Mat reduced = t.t() * bm * t;
  double trace = 0;
  for (int i = 0; i < free; ++i) trace += reduced.at<double>(i, i);
  for (int i = 0; i < free; ++i) reduced.at<double>(i, i) += 1e-9 * trace + 1e-12;  // unused levels
  const cv::Mat rhs = t.t() * (btym - bm * cm);
  cv::Mat z;
  cv::solve(reduced, rhs, z, cv::DECOMP_CHOLESKY);
  const cv::Mat xm = t * z + cm;
  for (int l = 0; l < kLevels; ++l) (*x)(l) = xm.at<double>(l);
  return yty + (x->t() * (b * *x - 2 * bty))(0);
}

}  // namespace

PaletteColours PaletteModel::fit(const Labels& labels, double* residual) const {
  PaletteColours colours{};
  std::array<Six, 2> btb{Six::zeros(), Six::zeros()};
  std::array<bool, kLevels> used{};
  for (int j = 0; j < kModelRegions; ++j)
    used[static_cast<std::size_t>(labels[static_cast<std::size_t>(j)])] = true;
  for (int system = 0; system < 2; ++system) {
    for (int j = 0; j < kModelRegions; ++j) {
      for (int k = 0; k < kModelRegions; ++k) {
        btb[static_cast<std::size_t>(system)](labels[static_cast<std::size_t>(j)],
                                              labels[static_cast<std::size_t>(k)]) +=
            ata(system, j, k);
      }
    }
  }
  // The palette's order, where the free fit breaks it (kMinLumaStep, kMinCbStep): a class's one
  // is held that much brighter (luminance) or yellower (lower Cb) than its zero, so that a
  // codeword asking for a colour the tag does not have pays for it in its residual instead of
  // fitting noise with a free extra colour.
  double total = 0;
  double range = 0;
  for (int ch = 0; ch < 3; ++ch) {
    const Six& b = btb[static_cast<std::size_t>(SystemOf(ch))];
    SixVector bty = SixVector::zeros();
    for (int j = 0; j < kModelRegions; ++j) {
      bty(labels[static_cast<std::size_t>(j)]) +=
          aty_[static_cast<std::size_t>(ch)][static_cast<std::size_t>(j)];
    }
    const double yty = yty_[static_cast<std::size_t>(ch)];
    SixVector x;
    double rss = SolveChannel(b, bty, yty, {}, &x);
    if (ch == 0) range = std::max(0.0, x(kQuietLevel) - x(kBlackLevel));
    if (ch < 2) {
      // Red has both levels in every codeword (the orientation cells); its step, as this photo
      // shows it (cast, exposure, saturation), sets the least step of green: the palette gives
      // green a larger luminance step than red (0.19 against 0.13) and the same step in Cb.
      const double least = ch == 0 ? kMinLumaStep * range : kMinCbStep;
      const auto step = [&](int zero, int one) {
        return ch == 0 ? x(one) - x(zero) : x(zero) - x(one);
      };
      std::vector<Tie> ties;
      const double sign = ch == 0 ? 1 : -1;
      double red_step = step(kRed0, kRed1);
      if (red_step < least) {
        ties.push_back({kRed0, kRed1, sign * least});
        red_step = least;
      }
      const double green_least =
          std::max(least, (ch == 0 ? kGreenLumaStepOfRed : kGreenCbStepOfRed) * red_step);
      if (used[kGreen0] && used[kGreen1] && step(kGreen0, kGreen1) < green_least) {
        ties.push_back({kGreen0, kGreen1, sign * green_least});
      }
      if (!ties.empty()) rss = SolveChannel(b, bty, yty, ties, &x);
    }
    for (int l = 0; l < kLevels; ++l)
      colours[static_cast<std::size_t>(l)][static_cast<std::size_t>(ch)] = x(l);
    total += weights_[static_cast<std::size_t>(ch)] * std::max(0.0, rss);
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
