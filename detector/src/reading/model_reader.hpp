#pragma once
// Reading a tag through a model of what the photo holds. The tag's regions are laid on the pixel
// grid; luminance (every pixel) and colour (Cb and Cr, one sample per 2 × 2 pixels, as a JPEG
// keeps them) are each the blurred coverage of the regions times their colours, with a blur of
// their own found by search (luminance: defocus, motion and a phone's sharpening; colour: the
// 4:2:0 block and whatever else smooths it). The corners are moved to where the model explains the
// luminance best, and the key is decided over the whole code at once (codeword_search.hpp), in
// units of each channel's own noise.

#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "pintag/detector/chroma_upsampling.hpp"
#include "reading/codeword_search.hpp"
#include "reading/edge_noise.hpp"
#include "reading/psf.hpp"
#include "reading/region_system.hpp"
#include "reading/residual_correlation.hpp"

namespace pintag::reading {

/// Corners C0 … C3 of a square, image pixels.
using Corners = std::array<cv::Point2d, 4>;

struct ModelFit {
  bool ok = false;
  Corners corners{};        ///< where the model put the square (the candidate's, refined)
  double corner_shift = 0;  ///< largest corner movement of the refinement, px
  LumaBlur luma_blur;
  ChromaBlur chroma_blur;
  /// How the luminance residual grows across edges; the luma samples are weighted by it
  /// (reading/edge_noise.hpp).
  EdgeNoise luma_edge_noise;
  double luma_noise = 0;    ///< residual standard deviation of the free model, luminance (0 … 1),
                            ///< of a sample inside one region
  double chroma_noise = 0;  ///< … Cb and Cr together
  std::size_t luma_samples = 0;
  std::size_t chroma_samples = 0;
  int evaluations = 0;  ///< models solved
  /// How the free model's Cb and Cr residuals correlate between neighbouring chroma blocks: the
  /// decision counts the codeword's lead in independent samples with it (reading/decision.hpp).
  ResidualCorrelation chroma_correlation;
};

/// The fitted model's normal equations and channel weights (1 / noise variance): all the decision
/// needs.
struct FittedModel {
  ModelFit fit;
  LumaSystem luma;
  ChromaSystem chroma;
  std::array<double, 3> weights{};  ///< luminance, Cb, Cr
  double free_residual = 0;         ///< the free model's weighted residual (its degrees of freedom)
};

struct ModelReading {
  ModelFit fit;
  CodewordDecision decision;
  std::string error;  ///< set when no model could be fitted
};

/// Largest square side (px) read this way: above it cells are several pixels wide, direct samples
/// read them, and the model's cost grows with the area.
inline constexpr double kModelMaxSidePx = 170;
/// Largest side (px) whose corners the model refines: above it the edge fit places them well
/// enough for cells of 7 px and more.
inline constexpr double kRefineCornersMaxSidePx = 72;

/// How far (px) the corner refinement may move each corner of a square of mean side `side_px`
/// from where it started: 8 % of the side, at least 1 and at most 3 px; 0 above
/// kRefineCornersMaxSidePx, where corners are not refined.
double MaxCornerShiftPx(double side_px);

/// Fits the model to the square starting at the corners `start` in `bgr` (8-bit BGR, its colour
/// decoded with `upsampling`): blur search, corners refined (squares up to
/// kRefineCornersMaxSidePx), final fit. fit.ok false and `error` set when it cannot.
FittedModel FitModel(const cv::Mat& bgr, ChromaUpsampling upsampling, const Corners& start,
                     std::string* error);

/// The codeword that explains a fitted model best, and by how much (codeword_search.hpp).
CodewordDecision DecideCodeword(const FittedModel& fitted);

/// FitModel, then DecideCodeword; the fitted model into `fitted` when given (for probes that score
/// other codewords on it).
ModelReading ReadThroughModel(const cv::Mat& bgr, ChromaUpsampling upsampling,
                              const Corners& corners, FittedModel* fitted = nullptr);

}  // namespace pintag::reading
