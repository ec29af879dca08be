#include "reading/model_reader.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "homography.hpp"
#include "reading/region_fit.hpp"
#include "reading/region_system.hpp"
#include "reading/tag_samples.hpp"

namespace pintag::reading {
namespace {

constexpr std::size_t kSearchSamples = 300;  // luminance samples while searching the blur
constexpr std::size_t kCornerSamples = 600;  // … while refining the corners
constexpr std::size_t kFinalSamples = 2500;  // … of the final fit
constexpr double kMaxSigmaPx = 2.7;

cv::Matx33d Homography(const Corners& c) {
  return stage::HomographyFromQuad({c[0], c[1], c[2], c[3]});
}

std::size_t StrideFor(std::size_t samples, std::size_t wanted) {
  return std::max<std::size_t>(1, samples / wanted);
}

// The observations and the grid they are modelled on, for one placement of the square. The grid
// is handed on from step to step (round blur, corners, shape and colours) rather than laid again
// for the same corners: laying it is a twentieth of a model read.
struct Placement {
  const TagSamples& samples;
  Corners corners;
  std::unique_ptr<const RegionCoverage> coverage;
  Placement(const TagSamples& s, const Corners& c)
      : Placement(s, c, std::make_unique<RegionCoverage>(Homography(c), CoverageBox(s.bounds))) {}
  Placement(const TagSamples& s, const Corners& c, std::unique_ptr<const RegionCoverage> grid)
      : samples(s), corners(c), coverage(std::move(grid)) {}
};

double LumaResidual(const Placement& p, const LumaBlur& blur, std::size_t stride,
                    bool by_position = false) {
  const FreeFit<1> fit =
      SolveFree(AccumulateLuma(*p.coverage, p.samples.luma, MakeKernel(blur), stride, by_position));
  return fit.ok ? fit.residual[0] : 1e300;
}

// A blur the search chose, and its residual on the placement it was searched on.
struct BlurChoice {
  LumaBlur blur;
  double residual = 1e300;
};

// The luminance blur, by a small search on the free model's residual. Round blurs first (what
// the corners are refined with), then, with `shape`, elongated ones around `from`, steps of each
// axis and the angle, and sharpening. `from` is the round search's choice; when the placement is
// still the one it was chosen on, its residual is known and not solved again. A step the clamps
// bring back onto a blur already tried (the minor axis of a round blur lengthened, the largest
// blur enlarged) is not solved again either: it could not win.
BlurChoice SearchLumaBlur(const Placement& p, bool shape, const BlurChoice& from,
                          bool from_placement_same, int* evaluations) {
  const std::size_t stride = StrideFor(p.samples.luma.size(), kSearchSamples);
  BlurChoice best{from.blur};
  std::vector<LumaBlur> tried;
  tried.reserve(16);
  const auto consider = [&](LumaBlur blur) {
    blur.major = std::clamp(blur.major, 0.25, kMaxSigmaPx);
    blur.minor = std::clamp(blur.minor, 0.25, blur.major);
    if (std::find(tried.begin(), tried.end(), blur) != tried.end()) return;
    tried.push_back(blur);
    ++*evaluations;
    const double r = LumaResidual(p, blur, stride);
    if (r < best.residual) best = {blur, r};
  };
  if (!shape) {
    for (const double sigma : {0.35, 0.6, 0.9, 1.3, 1.9, 2.7}) consider({sigma, sigma, 0, 0, 1});
    const double sigma = best.blur.major;
    for (const double f : {0.8, 1.2}) consider({sigma * f, sigma * f, 0, 0, 1});
    return best;
  }
  if (from_placement_same && from.residual < 1e300) {
    tried.push_back(from.blur);
    best = from;
  } else {
    consider(from.blur);
  }
  const LumaBlur round = best.blur;
  for (const double angle : {0.0, 45.0, 90.0, 135.0}) {
    consider({round.major * 1.6, round.minor / 1.25, angle, 0, 1});
  }
  const LumaBlur centre = best.blur;
  for (const double f : {1.25, 0.8}) {
    LumaBlur b = centre;
    b.major *= f;
    consider(b);
    b = centre;
    b.minor *= f;
    consider(b);
  }
  if (centre.major > centre.minor * 1.1) {
    for (const double turn : {22.5, -22.5}) {
      LumaBlur b = centre;
      b.angle_deg += turn;
      consider(b);
    }
  }
  const LumaBlur unsharpened = best.blur;
  for (const double amount : {0.5, 1.0}) {
    LumaBlur b = unsharpened;
    b.sharpen = amount;
    consider(b);
  }
  return best;
}

// The chroma blur with the system it was chosen on and that system's free fit (the model's own).
struct ChromaSearch {
  ChromaBlur blur;
  ChromaSystem system;
  FreeFit<2> free;
};

ChromaSearch SearchChromaBlur(const Placement& p, int* evaluations) {
  ChromaSearch best;
  double best_residual = 1e300;
  bool found = false;
  for (const double sigma : {0.3, 0.6, 0.9, 1.3, 1.8, 2.4}) {
    ++*evaluations;
    ChromaSystem system =
        AccumulateChroma(*p.coverage, p.samples.chroma, MakeKernel(ChromaBlur{sigma}));
    const FreeFit<2> fit = SolveFree(system);
    const double r = fit.ok ? fit.residual[0] + fit.residual[1] : 1e300;
    if (r < best_residual) {
      best_residual = r;
      best.blur = {sigma};
      best.system = system;
      best.free = fit;
      found = true;
    }
  }
  if (!found) {  // no blur gave a fit: the default blur's system and fit, as the model took before
    best.system = AccumulateChroma(*p.coverage, p.samples.chroma, MakeKernel(best.blur));
    best.free = SolveFree(best.system);
  }
  return best;
}

// Gauss–Newton on the eight corner coordinates, the blur held, the free colours re-solved at each
// step. The edge fit puts an edge where a blurred step crosses its midpoint; on a small, blurred or
// steep tag the elements and the quiet zone pull that crossing a pixel or more, and cells 3 px
// across do not survive that. The Jacobian is the Lucas–Kanade one: moving a corner moves each
// tag point by the homography's change, and the predicted luminance there changes by its
// gradient along that motion (colours held). Returns the best placement seen (`start` when no
// step lowered the residual).
Placement RefineCorners(Placement start, const LumaBlur& blur, int* evaluations) {
  const TagSamples& samples = start.samples;
  const Corners origin = start.corners;
  const Kernel kernel = MakeKernel(blur);
  std::vector<LumaSample> used;
  const std::size_t stride = StrideFor(samples.luma.size(), kCornerSamples);
  for (std::size_t i = 0; i < samples.luma.size(); i += stride) used.push_back(samples.luma[i]);
  const cv::Rect box = CoverageBox(samples.bounds);
  // The predicted image is read only at each used sample and its four neighbours (its value and
  // central-difference gradient there), so it is predicted there alone rather than over every
  // pixel of the samples' bounds (the same values; 9 % of this function's time on load frames).
  const cv::Rect dense_box(samples.bounds.x - 1, samples.bounds.y - 1, samples.bounds.width + 2,
                           samples.bounds.height + 2);
  std::vector<int> slot(static_cast<std::size_t>(dense_box.area()), -1);
  std::vector<LumaSample> needed;
  const auto slot_of = [&](int x, int y) -> int& {
    return slot[static_cast<std::size_t>((y - dense_box.y) * dense_box.width + x - dense_box.x)];
  };
  for (const LumaSample& s : used) {
    for (const cv::Point d :
         {cv::Point(0, 0), cv::Point(-1, 0), cv::Point(1, 0), cv::Point(0, -1), cv::Point(0, 1)}) {
      int& index = slot_of(s.x + d.x, s.y + d.y);
      if (index >= 0) continue;
      index = static_cast<int>(needed.size());
      needed.push_back({s.x + d.x, s.y + d.y, 0});
    }
  }
  const auto solve = [&](const RegionCoverage& coverage,
                         std::array<double, kModelRegions>* colours) {
    const FreeFit<1> fit = SolveFree(AccumulateLuma(coverage, used, kernel));
    ++*evaluations;
    if (!fit.ok) return 1e300;
    *colours = fit.colour[0];
    return fit.residual[0];
  };
  const double max_total = MaxCornerShiftPx(stage::MeanSidePx(Homography(origin)));
  std::array<double, kModelRegions> colours{};
  double residual = solve(*start.coverage, &colours);
  if (residual >= 1e300) return start;  // no free fit at the start
  Corners corners = origin;
  std::unique_ptr<const RegionCoverage> coverage = std::move(start.coverage);
  double lambda = 1e-3;
  constexpr double kStep = 0.05;  // px, the homography's change per coordinate
  for (int iteration = 0; iteration < 4; ++iteration) {
    const std::vector<double> predicted = PredictLuma(*coverage, needed, kernel, colours);
    const auto at = [&](int x, int y) {
      return predicted[static_cast<std::size_t>(slot_of(x, y))];
    };
    const cv::Matx33d h = Homography(corners);
    const cv::Matx33d to_tag = h.inv();
    std::array<cv::Matx33d, 8> moved;
    for (int k = 0; k < 8; ++k) {
      Corners c = corners;
      (k % 2 == 0 ? c[static_cast<std::size_t>(k / 2)].x : c[static_cast<std::size_t>(k / 2)].y) +=
          kStep;
      moved[static_cast<std::size_t>(k)] = Homography(c);
    }
    cv::Matx<double, 8, 8> jtj = cv::Matx<double, 8, 8>::zeros();
    cv::Matx<double, 8, 1> jtr = cv::Matx<double, 8, 1>::zeros();
    for (const LumaSample& s : used) {
      const double gx = (at(s.x + 1, s.y) - at(s.x - 1, s.y)) / 2;
      const double gy = (at(s.x, s.y + 1) - at(s.x, s.y - 1)) / 2;
      const cv::Vec3d t = to_tag * cv::Vec3d(s.x, s.y, 1);
      std::array<double, 8> j{};
      for (int k = 0; k < 8; ++k) {
        const cv::Vec3d q = moved[static_cast<std::size_t>(k)] * t;
        const double dx = (q[0] / q[2] - s.x) / kStep, dy = (q[1] / q[2] - s.y) / kStep;
        j[static_cast<std::size_t>(k)] = -(gx * dx + gy * dy);
      }
      const double r = s.value - at(s.x, s.y);
      for (int a = 0; a < 8; ++a) {
        jtr(a) += j[static_cast<std::size_t>(a)] * r;
        for (int b = a; b < 8; ++b)
          jtj(a, b) += j[static_cast<std::size_t>(a)] * j[static_cast<std::size_t>(b)];
      }
    }
    for (int a = 0; a < 8; ++a) {
      for (int b = 0; b < a; ++b) jtj(a, b) = jtj(b, a);
    }
    bool improved = false;
    double largest = 0;
    for (int attempt = 0; attempt < 3 && !improved; ++attempt) {
      cv::Matx<double, 8, 8> damped = jtj;
      for (int a = 0; a < 8; ++a) damped(a, a) *= 1 + lambda;
      cv::Matx<double, 8, 1> delta;
      if (!cv::solve(damped, jtr, delta, cv::DECOMP_CHOLESKY)) break;
      Corners next = corners;
      largest = 0;
      for (std::size_t k = 0; k < 4; ++k) {
        cv::Point2d d(delta(static_cast<int>(2 * k)), delta(static_cast<int>(2 * k + 1)));
        const double n = cv::norm(d);
        if (n > 1.0) d *= 1.0 / n;  // at most a pixel per step
        next[k] += d;
        const cv::Point2d total = next[k] - origin[k];
        if (cv::norm(total) > max_total)
          next[k] = origin[k] + total * (max_total / cv::norm(total));
        largest = std::max(largest, cv::norm(next[k] - corners[k]));
      }
      std::array<double, kModelRegions> next_colours{};
      auto next_coverage = std::make_unique<const RegionCoverage>(Homography(next), box);
      const double next_residual = solve(*next_coverage, &next_colours);
      if (next_residual < residual) {
        corners = next, colours = next_colours, residual = next_residual;
        coverage = std::move(next_coverage);
        lambda = std::max(1e-4, lambda / 4);
        improved = true;
      } else {
        lambda *= 8;
      }
    }
    if (!improved || largest < 0.02) break;
  }
  return {samples, corners, std::move(coverage)};
}

// The free chroma model's residuals at every chroma sample, for their correlation.
std::vector<GridResidual> ChromaResiduals(const Placement& p, const ChromaBlur& blur,
                                          const FreeFit<2>& free) {
  const Kernel kernel = MakeKernel(blur);
  std::vector<GridResidual> residuals;
  residuals.reserve(p.samples.chroma.size());
  SampleWeights w;
  for (const ChromaSample& s : p.samples.chroma) {
    p.coverage->blurred(kernel, s.x, s.y, w);
    double cb = 0, cr = 0;
    for (const int region : w.touched) {
      const auto r = static_cast<std::size_t>(region);
      cb += w.weight[r] * free.colour[0][r];
      cr += w.weight[r] * free.colour[1][r];
    }
    w.clear();
    residuals.push_back({s.x, s.y, {s.cb - cb, s.cr - cr}});
  }
  return residuals;
}

}  // namespace

double MaxCornerShiftPx(double side_px) {
  return side_px <= kRefineCornersMaxSidePx ? std::clamp(0.08 * side_px, 1.0, 3.0) : 0.0;
}

FittedModel FitModel(const cv::Mat& bgr, ChromaUpsampling upsampling, const Corners& start,
                     std::string* error) {
  FittedModel model;
  ModelFit& fit = model.fit;
  fit.corners = start;
  const double side = stage::MeanSidePx(Homography(start));
  if (side > kModelMaxSidePx || side < 8) {
    *error = "square too large or too small for the model";
    return model;
  }
  const TagSamples samples = SampleTag(bgr, upsampling, Homography(start));
  if (samples.luma.size() < 64 || samples.chroma.size() < 16) {
    *error = "too few samples for the model";
    return model;
  }
  Placement round(samples, start);
  const BlurChoice round_blur =
      SearchLumaBlur(round, /*shape=*/false, {}, /*from_placement_same=*/false, &fit.evaluations);
  const Placement placed = side <= kRefineCornersMaxSidePx
                               ? RefineCorners(std::move(round), round_blur.blur, &fit.evaluations)
                               : std::move(round);
  fit.corners = placed.corners;
  for (std::size_t k = 0; k < 4; ++k) {
    fit.corner_shift = std::max(fit.corner_shift, cv::norm(fit.corners[k] - start[k]));
  }
  // RefineCorners hands back the starting grid unless a step lowered the residual.
  const bool unmoved = placed.corners == start;
  fit.luma_blur =
      SearchLumaBlur(placed, /*shape=*/true, round_blur, unmoved, &fit.evaluations).blur;
  const ChromaSearch chroma = SearchChromaBlur(placed, &fit.evaluations);
  fit.chroma_blur = chroma.blur;
  const LumaRows luma_rows =
      GatherLumaRows(*placed.coverage, samples.luma, MakeKernel(fit.luma_blur),
                     StrideFor(samples.luma.size(), kFinalSamples));
  // The samples are weighted by the contrast under them (reading/edge_noise.hpp) only here: the
  // weights need the final placement's free colours, so the blur and corners above are searched
  // on the unweighted residual.
  model.luma = AccumulateLuma(luma_rows);
  FreeFit<1> free_luma = SolveFree(model.luma);
  if (free_luma.ok) {
    const std::vector<double> contrast = SampleContrast(luma_rows, free_luma.colour[0]);
    const EdgeNoise edge_noise = FitEdgeNoise(luma_rows, contrast, free_luma.colour[0]);
    LumaSystem weighted = AccumulateLuma(luma_rows, EdgeNoiseWeights(edge_noise, contrast));
    const FreeFit<1> free_weighted = SolveFree(weighted);
    if (free_weighted.ok) {
      model.luma = weighted;
      free_luma = free_weighted;
      fit.luma_edge_noise = edge_noise;
    }
  }
  model.chroma = chroma.system;
  const FreeFit<2>& free_chroma = chroma.free;
  if (!free_luma.ok || !free_chroma.ok) {
    *error = "model fit failed";
    return model;
  }
  // Each channel's noise: the free model's residual per degree of freedom (model error included).
  // The free chroma fit spends one colour per region in each of Cb and Cr, so it has twice the
  // regions' unknowns: counting them once made a small tag's chroma noise look smaller than it is
  // and its colour evidence (in noise units) larger, one way a wrong codeword could win by a lead.
  const auto variance = [](double residual, std::size_t samples_used, int channels) {
    const double unknowns = static_cast<double>(channels) * kModelRegions;
    return std::max(residual, 1e-12) /
           std::max(1.0,
                    static_cast<double>(channels) * static_cast<double>(samples_used) - unknowns);
  };
  const double luma_variance = variance(free_luma.residual[0], model.luma.samples, 1);
  const double chroma_variance =
      variance(free_chroma.residual[0] + free_chroma.residual[1], model.chroma.samples, 2);
  // Chroma blocks are 2 px apart (4:2:0).
  fit.chroma_correlation = NeighbourCorrelation(
      ChromaResiduals(placed, fit.chroma_blur, free_chroma), samples.bounds, 2);
  fit.luma_noise = std::sqrt(luma_variance);
  fit.chroma_noise = std::sqrt(chroma_variance);
  fit.luma_samples = model.luma.samples;
  fit.chroma_samples = model.chroma.samples;
  model.weights = {1 / luma_variance, 1 / chroma_variance, 1 / chroma_variance};
  model.free_residual = free_luma.residual[0] / luma_variance +
                        (free_chroma.residual[0] + free_chroma.residual[1]) / chroma_variance;
  fit.ok = true;
  return model;
}

CodewordDecision DecideCodeword(const FittedModel& fitted) {
  if (!fitted.fit.ok) return {};
  const PaletteModel model(fitted.luma, fitted.chroma, fitted.weights);
  CodewordDecision decision = SearchCodewords(model, SettleOrientations(model));
  decision.free_residual = fitted.free_residual;
  return decision;
}

ModelReading ReadThroughModel(const cv::Mat& bgr, ChromaUpsampling upsampling,
                              const Corners& corners, FittedModel* fitted) {
  ModelReading reading;
  const FittedModel model = FitModel(bgr, upsampling, corners, &reading.error);
  reading.fit = model.fit;
  if (model.fit.ok) reading.decision = DecideCodeword(model);
  if (fitted != nullptr) *fitted = model;
  return reading;
}

}  // namespace pintag::reading
