#include "candidates/borders.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <memory>
#include <opencv2/core/hal/intrin.hpp>

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
  // (rows + 2) × (cols + 2): a ring of zeros around the image. Left uninitialised where the image
  // is copied in: zeroing the whole of it first was a third of the copy's time.
  std::unique_ptr<std::int8_t[]> cells;
  std::array<std::ptrdiff_t, 16> step{};  // offset of neighbour k & 7, doubled for wrap-free search
};

// Rows are read 16 cells at a time, the last row's reads reaching past its padding column.
constexpr int kBlock = 16;

WorkImage Pad(const cv::Mat& binary) {
  WorkImage w;
  w.stride = binary.cols + 2;
  const auto stride = static_cast<std::size_t>(w.stride);
  const std::size_t size = stride * static_cast<std::size_t>(binary.rows + 2) + kBlock;
  w.cells = std::make_unique_for_overwrite<std::int8_t[]>(size);
  std::int8_t* cells = w.cells.get();
  std::fill_n(cells, stride + 1, kZero);  // the top row and the first row's left padding
  for (int y = 0; y < binary.rows; ++y) {
    const std::uint8_t* in = binary.ptr<std::uint8_t>(y);
    std::int8_t* out = cells + static_cast<std::ptrdiff_t>(y + 1) * w.stride + 1;
    for (int x = 0; x < binary.cols; ++x) out[x] = in[x] != 0 ? kUnseen : kZero;
    out[binary.cols] = out[binary.cols + 1] = kZero;  // this row's right padding, the next's left
  }
  // The bottom row (its first cell was set above) and the reads past it.
  std::fill(cells + stride * static_cast<std::size_t>(binary.rows + 1) + 1, cells + size, kZero);
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

// The first cell in [x, last] where a border starts, or last + 1. With `left` the cell before: an
// outer border starts at an unseen pixel after a zero; a hole border at a zero after a foreground
// pixel no border has left by its right side. (Raster order keeps `left` current: a border only
// relabels foreground, and one that starts at a zero relabels the cell before it.) Most cells
// of a textured region are borders already followed, so this looks for starts rather than for
// changes of value, sixteen cells a step.
int NextStart(const std::int8_t* row, int x, int last) {
#if CV_SIMD128
  const cv::v_int8x16 zero = cv::v_setzero_s8(), unseen = cv::v_setall_s8(kUnseen);
  for (; x <= last; x += kBlock) {
    const cv::v_int8x16 left = cv::v_load(row + x - 1), cell = cv::v_load(row + x);
    const cv::v_int8x16 starts =
        ((left == zero) & (cell == unseen)) | ((cell == zero) & (left > zero));
    const int mask = cv::v_signmask(starts);
    if (mask != 0) return std::min(last + 1, x + std::countr_zero(static_cast<unsigned>(mask)));
  }
  return last + 1;
#else
  for (; x <= last; ++x) {
    const std::int8_t left = row[x - 1], cell = row[x];
    if ((left == kZero && cell == kUnseen) || (cell == kZero && left > kZero)) return x;
  }
  return last + 1;
#endif
}

}  // namespace

std::vector<std::vector<cv::Point>> TraceBorders(const cv::Mat& binary, BorderSet which) {
  CV_Assert(binary.type() == CV_8UC1);
  WorkImage w = Pad(binary);
  std::vector<std::vector<cv::Point>> found;
  // Each border is followed into one reused buffer and then copied out at its size: most borders
  // are a few points, and growing a vector for each was half of this function's allocations.
  std::vector<cv::Point> points;
  const int last = binary.cols + 1;  // the right padding column too (it holds only zeros)
  for (int y = 1; y <= binary.rows; ++y) {
    std::int8_t* row = w.cells.get() + static_cast<std::ptrdiff_t>(y) * w.stride;
    for (int x = NextStart(row, 1, last); x <= last; x = NextStart(row, x + 1, last)) {
      const bool hole = row[x] == kZero;
      const int sx = hole ? x - 1 : x;
      const bool listed = which == BorderSet::kAll || !hole;
      points.clear();
      Follow(w, row + sx, {sx - 1, y - 1}, hole, listed ? &points : nullptr);
      if (listed) found.emplace_back(points.begin(), points.end());
    }
  }
  // OpenCV lists the borders last found first.
  std::reverse(found.begin(), found.end());
  return found;
}

}  // namespace pintag::stage
