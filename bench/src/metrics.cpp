#include "metrics.hpp"

#include <algorithm>
#include <limits>
#include <numbers>

namespace pintag::bench {
namespace {

cv::Point2d Centre(const std::array<cv::Point2d, 4>& c) {
  return (c[0] + c[1] + c[2] + c[3]) * 0.25;
}

double RotationErrorDeg(const cv::Matx33d& detected, const cv::Matx33d& truth) {
  const cv::Matx33d d = detected * truth.t();
  const double c = std::clamp((cv::trace(d) - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180 / std::numbers::pi;
}

}  // namespace

Outcome Score(const FrameSpec& frame, const std::vector<scene::MarkerTruth>& truth,
              const std::vector<Found>& found) {
  Outcome out;
  if (frame.tagless() || truth.empty()) {
    out.false_positives = static_cast<int>(found.size());
    return out;
  }
  const scene::MarkerTruth& t = truth.front();
  out.counted = t.fully_visible;
  const cv::Point2d centre = Centre(t.corners_px);
  for (const Found& f : found) {
    const bool on_tag = cv::norm(Centre(f.corners) - centre) < 0.3 * t.square_px;
    // A detection away from the tag read something in the background or the label's print, as
    // a tagless frame's would: counted apart from a tag read as another id.
    if (!on_tag) {
      ++out.off_tag;
      continue;
    }
    if (f.id != t.id) {
      ++out.misreads;
      continue;
    }
    if (out.found) continue;  // a duplicate of the tag already scored
    out.found = true;
    double sum = 0;
    for (int i = 0; i < 4; ++i) sum += cv::norm(f.corners[i] - t.corners_px[i]);
    out.corner_error_px = sum / 4;
    if (f.has_pose) {
      out.rotation_error_deg = RotationErrorDeg(f.rotation, t.pose.rotation);
      out.translation_error_pct =
          100 * cv::norm(f.translation - t.pose.translation) / cv::norm(t.pose.translation);
    }
  }
  return out;
}

void MarkerStats::add(const FrameSpec& frame, const Outcome& outcome) {
  if (frame.tagless()) {
    ++tagless_frames;
    false_positives += outcome.false_positives;
    false_positive_frames += outcome.false_positives > 0;
    return;
  }
  ++tagged_frames;
  misreads += outcome.misreads;
  off_tag += outcome.off_tag;
  if (!outcome.counted) {
    ++excluded;
    return;
  }
  Tally& bin = grid[frame.hard][frame.size_index][frame.tilt_index];
  ++bin.tags;
  bin.found += outcome.found;
  poses.push_back({frame.index, frame.hard, frame.size_index, frame.tilt_index, outcome.found});
  if (!outcome.found) return;
  corner_error_px[frame.size_index].push_back(outcome.corner_error_px);
  if (!std::isnan(outcome.rotation_error_deg)) {
    rotation_error_deg.push_back(outcome.rotation_error_deg);
    translation_error_pct.push_back(outcome.translation_error_pct);
  }
}

Tally MarkerStats::recall(int hard, int size_index, int tilt_index) const {
  Tally sum;
  for (int h = 0; h < 2; ++h) {
    if (hard >= 0 && h != hard) continue;
    for (int s = 0; s < kSizeCount; ++s) {
      if (size_index >= 0 && s != size_index) continue;
      for (int t = 0; t < kTiltCount; ++t) {
        if (tilt_index >= 0 && t != tilt_index) continue;
        sum.add(grid[h][s][t]);
      }
    }
  }
  return sum;
}

std::vector<double> MarkerStats::allCornerErrors() const {
  std::vector<double> all;
  for (const auto& v : corner_error_px) all.insert(all.end(), v.begin(), v.end());
  return all;
}

double Mean(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (const double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double Percentile(std::vector<double> values, double percent) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double pos = percent / 100 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (values[hi] - values[lo]) * (pos - static_cast<double>(lo));
}

}  // namespace pintag::bench
