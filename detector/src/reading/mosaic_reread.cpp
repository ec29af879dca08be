#include "reading/mosaic_reread.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <string>

#include "elapsed_ms.hpp"
#include "reading/decision.hpp"

namespace pintag::reading {

bool NeedsMosaicCheck(const ModelReading& reading) {
  const double independent_lead =
      CountedLead(reading) / VarianceInflation(reading.fit.chroma_correlation);
  // Written so that a lead that is not a number is checked.
  return !(independent_lead >= kMosaicCheckMaxIndependentLead);
}

SquareCrop CropAroundCorners(const cv::Mat& bgr, const Corners& corners) {
  SquareCrop crop;
  double left = corners[0].x, right = left, top = corners[0].y, bottom = top;
  for (const cv::Point2d& c : corners) {
    if (!std::isfinite(c.x) || !std::isfinite(c.y)) return crop;
    left = std::min(left, c.x), right = std::max(right, c.x);
    top = std::min(top, c.y), bottom = std::max(bottom, c.y);
  }
  const auto clamp = [](double v, int hi) {
    return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(hi)));
  };
  // Rounded down to even: a 4:2:0 chroma block starts at even coordinates in the frame.
  const int x0 = clamp(std::floor(left) - kMosaicCropMarginPx, bgr.cols) & ~1;
  const int y0 = clamp(std::floor(top) - kMosaicCropMarginPx, bgr.rows) & ~1;
  const int x1 = clamp(std::ceil(right) + kMosaicCropMarginPx + 1, bgr.cols);
  const int y1 = clamp(std::ceil(bottom) + kMosaicCropMarginPx + 1, bgr.rows);
  if (x1 <= x0 || y1 <= y0) return crop;
  crop.bgr = bgr(cv::Rect(x0, y0, x1 - x0, y1 - y0));
  const cv::Point2d origin(x0, y0);
  for (std::size_t k = 0; k < corners.size(); ++k) crop.corners[k] = corners[k] - origin;
  return crop;
}

cv::Mat Remosaic(const cv::Mat& bgr, int phase) {
  // Where red sits in the 2 × 2 cell; blue sits diagonally from it and green on the other two.
  const int red_x = phase & 1, red_y = (phase >> 1) & 1;
  cv::Mat sensed(bgr.size(), CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* in = bgr.ptr<cv::Vec3b>(y);
    auto* out = sensed.ptr<std::uint8_t>(y);
    const bool red_row = (y & 1) == red_y;
    for (int x = 0; x < bgr.cols; ++x) {
      const bool red_column = (x & 1) == red_x;
      const int channel = red_row == red_column ? (red_row ? 2 : 0) : 1;  // BGR order
      out[x] = in[x][channel];
    }
  }
  constexpr std::array<int, kMosaicPhases> kBilinearCodes = {
      cv::COLOR_BayerRGGB2BGR, cv::COLOR_BayerGRBG2BGR, cv::COLOR_BayerGBRG2BGR,
      cv::COLOR_BayerBGGR2BGR};
  cv::Mat demosaiced;
  cv::demosaicing(sensed, demosaiced, kBilinearCodes[static_cast<std::size_t>(phase & 3)]);
  return demosaiced;
}

MosaicReread ReadThroughMosaic(const SquareCrop& crop, ChromaUpsampling upsampling, TagKey winner,
                               int phase) {
  using Clock = std::chrono::steady_clock;
  MosaicReread reread;
  if (crop.bgr.empty()) return reread;
  const auto t0 = Clock::now();
  const cv::Mat sensed = Remosaic(crop.bgr, phase);
  ModelReading again;
  const FittedModel model = FitModel(sensed, upsampling, crop.corners, &again.error);
  again.fit = model.fit;
  const auto t1 = Clock::now();
  reread.fit_ms = ElapsedMs(t0, t1);
  if (!model.fit.ok || TooSmallToRead(model.fit.corners)) return reread;
  again.decision = DecideCodeword(model);
  reread.codeword_ms = ElapsedMs(t1, Clock::now());
  reread.accepted_again =
      again.decision.winner && *again.decision.winner == winner && RefuseCodeword(again).empty();
  return reread;
}

}  // namespace pintag::reading
