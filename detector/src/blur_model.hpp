#pragma once
// Stage 5b, reading cells through a blur model. On a small or blurred tag each pixel mixes several
// cells (a green sector of a 32 px tag is about 4 px across; motion blur smears 5), so sampling
// near a cell's centre reads its neighbours too. Here every cell's colour is estimated at once
// instead: each pixel near the tag is modelled, in linear light, as the camera's blur applied to
// the tag's 50 regions (48 cells, the black square, the quiet zone), and the region colours that
// explain the pixels best are found by least squares. The blur is a Gaussian, round or elongated
// (as motion makes it), chosen by a small search for the smallest residual.
//
// The estimates come back as cell samples for the same orientation and codec checks as direct
// samples: nothing here decides a bit, so a tag read this way meets the same bar.

#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "pintag/codec/cells.hpp"
#include "pintag/detector/detection.hpp"
#include "sampling.hpp"

namespace pintag::stage {

/// The tag's regions in the model: the quiet zone, the black square, then per element its 4 red
/// quadrants and 8 green sectors.
inline constexpr std::size_t kModelRegions = 2 + kElements * (kRedQuadrants + kGreenSectors);

/// The model region of a point in tag units: 0 outside the square, 1 black, then element e's red
/// quadrant q at 2 + 12 e + q and green sector s at 2 + 12 e + 4 + s (geometry::LocateCell's
/// cells, found without trigonometry).
int ModelRegionAt(double x, double y);

/// The least-squares problem of the chosen blur, AᵀA x = Aᵀy over pixels × regions, kept so that
/// constrained readings (ReadBitsThroughBlur) can be scored without touching the pixels again.
/// Channels: brightness Y, then B − Y and R − Y (linear light); the colour differences see a wider
/// blur (chroma subsampling), hence their own AᵀA.
struct NormalEquations {
  std::array<double, kModelRegions * kModelRegions> ata{};         ///< brightness
  std::array<double, kModelRegions * kModelRegions> ata_chroma{};  ///< colour differences
  std::array<double, kModelRegions * 3> aty{};
  std::array<double, 3> yty{};  ///< per channel: the channels' noise differs (NearestCodeword…)
  std::size_t pixels = 0;
};

/// Widest blur the fit tries, px (standard deviation along the blur's long axis): 5 px of motion
/// with 2 px of defocus. A fit that ends here has met a blur it cannot model.
inline constexpr double kBlurFitMaxSigmaPx = 2.5;

struct BlurFit {
  bool ok = false;
  CellSamples cells;           ///< each cell's fitted colour, as a*, b*
  double sigma_major_px = 0;   ///< the chosen blur: standard deviation along its long axis, px
  double sigma_minor_px = 0;   ///< … and across it, px
  double angle_deg = 0;        ///< direction of the long axis (image x towards y)
  double chroma_extra_px = 0;  ///< extra blur of colour over brightness (chroma subsampling), px
  double rms = 0;              ///< residual per pixel and channel, linear light (0 … 1)
  int evaluations = 0;         ///< blur candidates tried
  NormalEquations equations;   ///< of the chosen blur, over all observed pixels
  /// The blur search ended at its widest blur: the pixels are blurred at least that much, and
  /// the model's colours and residuals are the less trustworthy.
  bool atBlurLimit() const { return sigma_major_px >= kBlurFitMaxSigmaPx - 1e-9; }
};

/// Largest square side (px) the fit is tried on: above it cells are several pixels wide, direct
/// samples read them, and the fit's cost grows with the area.
inline constexpr double kBlurFitMaxSidePx = 170;

/// Fits the cells of the tag whose unit square maps to the image by `tag_to_image`.
BlurFit FitCellsThroughBlur(const cv::Mat& bgr, const cv::Matx33d& tag_to_image);

/// Mean squared brightness residual per pixel (linear light) of the free model with the tag at
/// `tag_to_image` and the blur of `fit` held: what a corner search minimises. The pixels are the
/// observed ones whose hashed image position is a multiple of `pixel_stride`, so that residuals
/// of nearby corner positions are over (nearly) the same pixels. Brightness carries the square's
/// edges and the cells' outlines, and alone halves the work. Infinity when the tag is out of the
/// model's range or the solve fails.
double ResidualAtFittedBlur(const cv::Mat& bgr, const cv::Matx33d& tag_to_image, const BlurFit& fit,
                            std::size_t pixel_stride);
/// The `pixel_stride` for a square of that area (px²): about 600 pixels per residual.
std::size_t CornerSearchStride(double square_area_px);

/// Bits read from a blur fit by a stronger model: every cell takes one of its class's two colours,
/// so the whole tag has only six (quiet zone, black, red 0/1, green 0/1) besides 48 binary
/// choices. For each of the four orientations the orientation cells are fixed to the format's
/// bits, the others chosen (iterated conditional modes, colours refitted in turn), and the
/// orientation explaining the pixels best wins if clearly better than the next. A bit is known
/// only when flipping it costs at least `min_significance` times the residual noise per value;
/// its margin is that cost over 4 × min_significance (capped at 1), signed.
struct ModelReading {
  bool ok = false;
  std::string error;
  int quarter_turns = 0;  ///< element `quarter_turns` of the sampled frame is C0
  CellReading reading;    ///< canonical orientation
  BitMargins margins;     ///< canonical orientation
  int unknown = 0;
  double min_known_margin = 1e9;
};

/// The two-colours-per-class model settled in one orientation: each region's level (0 quiet
/// zone, 1 black, 2/3 red 0/1, 4/5 green 0/1), the six colours (Y, B − Y, R − Y) and the residual.
struct SettledOrientation {
  std::array<int, kModelRegions> labels{};
  std::array<std::array<double, 3>, 6> colours{};
  double residual = 1e300;
};
/// All four orientations (element r of the sampled frame taken as C0), orientation cells fixed to
/// the format's bits: the work both readers below start from, computed once for both.
using SettledOrientations = std::array<SettledOrientation, 4>;
SettledOrientations SettleOrientations(const BlurFit& fit);

ModelReading ReadBitsThroughBlur(const BlurFit& fit, const SettledOrientations& settled,
                                 double min_significance = 9);

/// The format codeword nearest to a blur fit, for when no reading of single bits decodes: every
/// (key, orientation) is ranked by the flip costs of the cells where it disagrees with the settled
/// reading of that orientation, the best 256 are scored exactly (colours refitted), then every
/// codeword within 7 cells of the winner (again around a new winner), and the best is accepted
/// only if it explains the pixels better than any other codeword scored by `min_margin` times
/// the residual noise (each channel's own, under the free reading), at least as well as the free
/// reading, and its colours look like the palette. This is a dictionary decode with a margin, as
/// ArUco and AprilTag do, but on the fitted model rather than on thresholded bits. With
/// `excuse_small_excess`, a winner leading by at least 100 noise units may explain the pixels worse
/// than the free reading by up to a tenth of its lead. The lead (noise units) a nearest codeword
/// needs over every other codeword.
inline constexpr double kNearestCodewordMinLead = 25;

struct CodewordReading {
  std::optional<TagKey> key;
  std::optional<TagKey> winner;  ///< the codeword explaining the pixels best, also when refused
  std::string error;
  int quarter_turns = 0;  ///< element `quarter_turns` of the sampled frame is C0
  CellReading reading;    ///< the codeword, canonical
  double lead = 0;        ///< runner-up's residual over the winner's, in noise units (also set
                          ///< when refused for the margin)
  double excess = 0;      ///< winner's residual over the free reading's, in noise units
};

CodewordReading NearestCodewordThroughBlur(const BlurFit& fit, const SettledOrientations& settled,
                                           double min_margin = kNearestCodewordMinLead,
                                           bool excuse_small_excess = true);

}  // namespace pintag::stage
