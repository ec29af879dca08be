#pragma once
// What the photo holds around a tag, as a JPEG holds it: brightness at every pixel, colour once per
// 2 × 2 pixels (4:2:0). These are the observations every model of the tag is fitted to; they are
// taken once per candidate, whatever corners the model then tries.

#include <opencv2/core.hpp>
#include <vector>

#include "pintag/detector/chroma_upsampling.hpp"

namespace pintag::reading {

/// One pixel's brightness: linear-light luminance of its decoded colour (light mixes linearly
/// there: blur and a pixel's area act before the camera's tone curve).
struct LumaSample {
  int x = 0, y = 0;  ///< image pixel
  double value = 0;  ///< 0 … 1
};

/// One 2 × 2 block's colour differences as JPEG stores them (BT.601 Cb and Cr of the sRGB values,
/// −0.5 … 0.5), the block at even image coordinates as JPEG's chroma blocks are. They are taken
/// from the decoded pixels with the decoder's upsampling, where there was one, undone
/// (UndoChromaUpsampling), so that they are close to the samples the file stores.
struct ChromaSample {
  int x = 0, y = 0;  ///< the block's top-left pixel
  double cb = 0, cr = 0;
};

struct TagSamples {
  std::vector<LumaSample> luma;
  std::vector<ChromaSample> chroma;
  cv::Rect bounds;  ///< pixels the samples occupy (chroma blocks whole)
};

/// Tag units beyond the square that are observed: the quiet zone's edge carries the square's.
inline constexpr double kObservedMargin = 0.06;

/// Jacobi steps of UndoChromaUpsampling: six leave the kernel's inverse within a few per cent at
/// every frequency, and were what the reader probe measured (docs/DETECTOR-RESEARCH.md, tenth
/// sitting).
inline constexpr int kUndoUpsamplingSteps = 6;

/// Undoes, on a grid of 2 × 2 block means of decoded Cb or Cr, the decoder's chroma upsampling:
/// libjpeg's default for 4:2:0 interpolates each pixel from its block's sample (9/16) and the
/// three nearest neighbours' (3/16, 3/16, 1/16), so that a block's mean is the stored samples
/// blurred by [1 6 1]/8 each way, and a chroma model fitted to those means sees colour twice
/// blurred. 4:2:2 (and 4:4:0) interpolate along one axis only, [3 1]/4, so the blur is [1 6 1]/8
/// along that axis alone. Edges repeat the grid's border. A grid under 3 samples along an
/// interpolated axis, and kNone, leave the means as they are.
void UndoChromaUpsampling(cv::Mat* block_means, ChromaUpsampling upsampling);

/// The samples within kObservedMargin of the square that `tag_to_image` maps the unit square to,
/// inside `bgr` (8-bit BGR, its colour decoded with `upsampling`) and at least `border` pixels
/// from its edge. Empty when the square is not wholly in front of the camera.
TagSamples SampleTag(const cv::Mat& bgr, ChromaUpsampling upsampling,
                     const cv::Matx33d& tag_to_image, int border = 0);

}  // namespace pintag::reading
