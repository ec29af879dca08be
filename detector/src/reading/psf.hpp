#pragma once
// The camera's point-spread function as the reading model uses it: how much of the light a pixel
// (or a chroma sample) records comes from each nearby pixel's area.

#include <vector>

namespace pintag::reading {

/// Largest kernel reach, px, from a sample's anchor pixel.
inline constexpr int kMaxKernelRadius = 8;

/// The blur of brightness. Round, it is a Gaussian (defocus); elongated, a round Gaussian of
/// `minor` smeared evenly along a line at `angle_deg` to a spread of `major` (a camera moving
/// during the exposure). `sharpen` is a phone's unsharp mask on luma, which every phone applies:
/// the blurred image plus `sharpen` times its difference from itself blurred by another
/// `sharpen_sigma` px; it gives edges the over- and undershoot a Gaussian cannot.
struct LumaBlur {
  double major = 1;      ///< standard deviation along the long axis, px
  double minor = 1;      ///< across it, px (≤ major)
  double angle_deg = 0;  ///< direction of the long axis, image x towards y
  double sharpen = 0;    ///< unsharp-mask amount, 0 = none
  double sharpen_sigma = 1.0;

  bool operator==(const LumaBlur&) const = default;
};

/// The blur of a chroma sample: the 2 × 2 pixels JPEG averages into one sample (4:2:0), each the
/// scene blurred by a round Gaussian of `sigma` px (lens, demosaicing, colour noise reduction and
/// the decoder's upsampling together).
struct ChromaBlur {
  double sigma = 1;
};

/// A kernel by rows, each row dense from its first kept tap to its last, with running sums so that
/// a stretch of pixels lying in one region takes the stretch's weight in one addition. Offsets
/// are relative to the sample's anchor pixel (a luma pixel itself; a chroma sample's top-left
/// pixel of its 2 × 2 block).
struct KernelRow {
  int dy = 0;
  int dx_begin = 0;
  std::vector<double> weight;  ///< the tap at dx_begin + j
  std::vector<double> prefix;  ///< prefix[j]: weight[0] + … + weight[j − 1]
};
using Kernel = std::vector<KernelRow>;

Kernel MakeKernel(const LumaBlur& blur);
Kernel MakeKernel(const ChromaBlur& blur);

}  // namespace pintag::reading
