#include "reading/rereading.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <string>

#include "elapsed_ms.hpp"
#include "reading/decision.hpp"

namespace pintag::reading {

bool NeedsRereading(const Corners& fitted) {
  return IsNarrow(fitted);
}

Corners MovedCorners(const Corners& fitted, double sign) {
  constexpr std::array<double, 4> kDirectionsDeg = {20, 245, 110, 335};
  Corners moved = fitted;
  for (std::size_t k = 0; k < moved.size(); ++k) {
    const double a = kDirectionsDeg[k] * CV_PI / 180;
    moved[k] += sign * kRereadShiftPx * cv::Point2d(std::cos(a), std::sin(a));
  }
  return moved;
}

Reread ReadAgain(const cv::Mat& bgr, ChromaUpsampling upsampling, const Corners& start,
                 TagKey winner) {
  using Clock = std::chrono::steady_clock;
  Reread reread;
  const auto t0 = Clock::now();
  std::string error;
  const FittedModel model = FitModel(bgr, upsampling, start, &error);
  const auto t1 = Clock::now();
  reread.fit_ms = ElapsedMs(t0, t1);
  if (!model.fit.ok || TooSmallToRead(model.fit.corners)) return reread;
  const CodewordDecision decision = DecideCodeword(model);
  reread.codeword_ms = ElapsedMs(t1, Clock::now());
  reread.same_winner = decision.winner && *decision.winner == winner;
  return reread;
}

}  // namespace pintag::reading
