#include "reading/orientation.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pintag::stage {
namespace {

constexpr double kAssumedSpanB = 60;  // b* between 1 and 0 when no 0 can be seen (palette: ~75)

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

struct Hypothesis {
  bool ok = false;
  double one = 0;
  double zero = 0;
};

Hypothesis Try(const CellSamples& cells, const BitThresholds& t, const BasicCells<bool>& usable) {
  std::vector<double> zeros, ones;
  for (int e = 0; e < kElements; ++e) {
    for (int q = 0; q < kRedQuadrants; ++q) {
      if (q == InnerQuadrant(e) || !usable.red[e][q]) continue;
      (e == 0 ? zeros : ones).push_back(cells.red[e][q].b);
    }
  }
  Hypothesis h;
  if (ones.size() < 6) return h;
  const auto [min_one, max_one] = std::minmax_element(ones.begin(), ones.end());
  h.one = Median(ones);
  if (!zeros.empty()) {
    const double max_zero = *std::max_element(zeros.begin(), zeros.end());
    h.zero = Median(zeros);
    h.ok = *min_one - max_zero >= t.min_span_b * 0.5 && h.one - h.zero >= t.min_span_b;
    return h;
  }
  // C0 unseen: the nine ones must agree, and its absence must be real (all its cells unusable).
  for (int q = 0; q < kRedQuadrants; ++q) {
    if (usable.red[0][q]) return h;
  }
  if (*max_one - *min_one >= t.min_span_b * 0.5) return h;
  double darkest = h.one;
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      if (usable.green[e][s]) darkest = std::min(darkest, cells.green[e][s].b);
    }
    if (usable.red[e][InnerQuadrant(e)])
      darkest = std::min(darkest, cells.red[e][InnerQuadrant(e)].b);
  }
  h.zero = std::min(darkest, h.one - kAssumedSpanB);
  h.ok = true;
  return h;
}

}  // namespace

OrientationResult ReadOrientation(const CellSamples& samples, const BitThresholds& t) {
  OrientationResult result;
  BasicCells<bool> usable;
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      const CellSample& c = samples.green[e][s];
      usable.green[e][s] = c.valid && c.a <= t.green_cell_max_a;
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      const CellSample& c = samples.red[e][q];
      usable.red[e][q] = c.valid && c.a >= t.red_cell_min_a;
    }
  }

  int found = -1;
  Hypothesis chosen;
  for (int r = 0; r < 4; ++r) {
    const Hypothesis h = Try(RotateCells(samples, r), t, RotateCells(usable, r));
    if (!h.ok) continue;
    if (found >= 0) {
      result.error = "orientation ambiguous";
      return result;
    }
    found = r;
    chosen = h;
  }
  if (found < 0) {
    result.error = "no orientation fits the red quadrants";
    return result;
  }

  const CellSamples cells = RotateCells(samples, found);
  const BasicCells<bool> ok = RotateCells(usable, found);
  const double mid = (chosen.one + chosen.zero) / 2;
  const double half = (chosen.one - chosen.zero) / 2;
  result.quarter_turns = found;
  result.one_level = chosen.one;
  result.zero_level = chosen.zero;
  const auto read = [&](const CellSample& c, bool is_usable, Bit* bit, double* margin) {
    *margin = is_usable ? (c.b - mid) / half : 0;
    if (!is_usable || std::abs(*margin) < t.min_margin) {
      *bit = Bit::kUnknown;
      ++result.unknown;
      return;
    }
    *bit = *margin > 0 ? Bit::kOne : Bit::kZero;
    result.min_known_margin = std::min(result.min_known_margin, std::abs(*margin));
  };
  for (int e = 0; e < kElements; ++e) {
    for (int s = 0; s < kGreenSectors; ++s) {
      read(cells.green[e][s], ok.green[e][s], &result.reading.green[e][s],
           &result.margins.green[e][s]);
    }
    for (int q = 0; q < kRedQuadrants; ++q) {
      read(cells.red[e][q], ok.red[e][q], &result.reading.red[e][q], &result.margins.red[e][q]);
    }
  }
  result.ok = true;
  return result;
}

}  // namespace pintag::stage
