#include "duplicates.hpp"

#include <algorithm>
#include <cmath>

namespace pintag::stage {
namespace {

Point2 Centre(const Detection& d) {
  Point2 c{0, 0};
  for (const Point2& p : d.corners) c.x += p.x / 4, c.y += p.y / 4;
  return c;
}

bool SamePlace(const Detection& a, const Detection& b) {
  const Point2 ca = Centre(a), cb = Centre(b);
  return std::hypot(ca.x - cb.x, ca.y - cb.y) < 0.25 * std::max(a.square_px, b.square_px);
}

}  // namespace

void RemoveDuplicates(std::vector<Detection>* detections) {
  std::vector<Detection> kept;
  for (const bool decoded : {true, false}) {
    for (Detection& d : *detections) {
      if (d.key.has_value() != decoded) continue;
      const bool taken = std::any_of(kept.begin(), kept.end(),
                                     [&](const Detection& k) { return SamePlace(k, d); });
      if (!taken) kept.push_back(std::move(d));
    }
  }
  *detections = std::move(kept);
}

}  // namespace pintag::stage
