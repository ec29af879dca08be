#include "candidates/borders.hpp"

#include <array>
#include <cstdint>
#include <cstring>

namespace pintag::stage {
namespace {

// Pixel states in the padded work image. Suzuki and Abe label each border with its own number;
// only these classes decide where the next border starts, so one label each does.
constexpr std::int8_t kZero = 0;
constexpr std::int8_t kUnseen = 1;      // foreground no border has passed
constexpr std::int8_t kOnBorder = 2;    // passed by a border
constexpr std::int8_t kRightEdge = -2;  // passed by a border that found its right neighbour zero

// Chain code k: the neighbour in direction k, counter-clockwise on screen from "right".
constexpr std::array<int, 8> kDx = {1, 1, 0, -1, -1, -1, 0, 1};
constexpr std::array<int, 8> kDy = {0, -1, -1, -1, 0, 1, 1, 1};

struct WorkImage {
  int stride = 0;
  std::vector<std::int8_t> cells;  // (rows + 2) × (cols + 2): a ring of zeros around the image
  std::array<std::ptrdiff_t, 16> step{};  // offset of neighbour k & 7, doubled for wrap-free search
};

WorkImage Pad(const cv::Mat& binary) {
  WorkImage w;
  w.stride = binary.cols + 2;
  w.cells.assign(static_cast<std::size_t>(w.stride) * static_cast<std::size_t>(binary.rows + 2),
                 kZero);
  for (int y = 0; y < binary.rows; ++y) {
    const std::uint8_t* in = binary.ptr<std::uint8_t>(y);
    std::int8_t* out = w.cells.data() + static_cast<std::ptrdiff_t>(y + 1) * w.stride + 1;
    for (int x = 0; x < binary.cols; ++x) out[x] = in[x] != 0 ? kUnseen : kZero;
  }
  for (std::size_t k = 0; k < w.step.size(); ++k) {
    w.step[k] = kDy[k & 7] * static_cast<std::ptrdiff_t>(w.stride) + kDx[k & 7];
  }
  return w;
}

// Follows the border that starts at `start` (image coordinates `at`), labelling its pixels, and
// appends the ends of its straight runs to `points` when given. An outer border is entered from
// its left neighbour, a hole border from its right one.
void Follow(const WorkImage& w, std::int8_t* start, cv::Point at, bool hole,
            std::vector<cv::Point>* points) {
  // The first foreground neighbour clockwise from the entry side.
  const int entry = hole ? 0 : 4;
  int s = entry;
  std::int8_t* second = nullptr;
  do {
    s = (s - 1) & 7;
    second = start + w.step[static_cast<std::size_t>(s)];
  } while (*second == kZero && s != entry);
  if (*second == kZero) {  // a lone pixel
    *start = kRightEdge;
    if (points != nullptr) points->push_back(at);
    return;
  }
  std::int8_t* current = start;
  int last_direction = s ^ 4;  // differs from any first step: the start is always listed
  for (;;) {
    // Counter-clockwise from the pixel we came from, to the next foreground neighbour.
    const int came_from = s;
    std::int8_t* next = nullptr;
    for (;;) {
      next = current + w.step[static_cast<std::size_t>(++s)];
      if (*next != kZero) break;
    }
    s &= 7;
    // The search passed direction 0 (a zero to the right) exactly when it wrapped past it.
    if (static_cast<unsigned>(s - 1) < static_cast<unsigned>(came_from)) {
      *current = kRightEdge;
    } else if (*current == kUnseen) {
      *current = kOnBorder;
    }
    if (s != last_direction) {
      if (points != nullptr) points->push_back(at);
      last_direction = s;
    }
    at.x += kDx[static_cast<std::size_t>(s)];
    at.y += kDy[static_cast<std::size_t>(s)];
    if (next == start && current == second) return;
    current = next;
    s = (s + 4) & 7;
  }
}

}  // namespace

std::vector<std::vector<cv::Point>> TraceBorders(const cv::Mat& binary, BorderSet which) {
  CV_Assert(binary.type() == CV_8UC1);
  WorkImage w = Pad(binary);
  std::vector<std::vector<cv::Point>> found;
  constexpr std::uint64_t kBytes = 0x0101010101010101ULL;
  const int last = binary.cols + 1;  // the right padding column, where a hole can open
  for (int y = 1; y <= binary.rows; ++y) {
    std::int8_t* row = w.cells.data() + static_cast<std::ptrdiff_t>(y) * w.stride;
    std::int8_t previous = kZero;
    for (int x = 1; x <= last; ++x) {
      // Nothing starts inside a run of equal cells: skip it, eight cells a compare.
      const std::uint64_t run = kBytes * static_cast<std::uint8_t>(previous);
      for (; x + 8 <= last + 1; x += 8) {
        std::uint64_t cells;
        std::memcpy(&cells, row + x, sizeof cells);
        if (cells != run) break;
      }
      while (x <= last && row[x] == previous) ++x;
      if (x > last) break;
      const std::int8_t cell = row[x];
      // An outer border starts at an unseen pixel after a zero; a hole border at a foreground
      // pixel no border has left by its right side, before a zero.
      const bool outer = previous == kZero && cell == kUnseen;
      const bool hole = !outer && cell == kZero && previous >= kUnseen;
      if (outer || hole) {
        const int sx = hole ? x - 1 : x;
        const bool listed = which == BorderSet::kAll || outer;
        std::vector<cv::Point> points;
        Follow(w, row + sx, {sx - 1, y - 1}, hole, listed ? &points : nullptr);
        if (listed) found.push_back(std::move(points));
      }
      previous = row[x];  // following a border may have relabelled this cell
    }
  }
  // OpenCV lists the borders last found first.
  return {std::make_move_iterator(found.rbegin()), std::make_move_iterator(found.rend())};
}

}  // namespace pintag::stage
