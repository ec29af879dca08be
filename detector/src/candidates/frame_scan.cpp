#include "candidates/frame_scan.hpp"

#include <algorithm>
#include <cstdint>
#include <opencv2/core/hal/intrin.hpp>
#include <vector>

#include "candidates/quads.hpp"

namespace pintag::stage {
namespace {

// Runs of one redness level along a row.
class RunTracker {
 public:
  explicit RunTracker(std::vector<RedRun>* out) : out_(out) {}
  void step(bool red, int y, int x) {
    if (red && start_ < 0) start_ = x;
    if (!red && start_ >= 0) {
      out_->push_back({y, start_, x - 1});
      start_ = -1;
    }
  }
  void finish(int y, int cols) {
    if (start_ >= 0) out_->push_back({y, start_, cols - 1});
    start_ = -1;
  }

 private:
  std::vector<RedRun>* out_;
  int start_ = -1;
};

// One pixel: the faint level is a template switch so that the common loop carries no per-pixel
// test for it. When the faint thresholds are both at most the main ones (the detector's
// defaults), every main-red pixel is faint-red, and the faint table is looked up first: most
// pixels of a photograph fail it, and the main table is not read for them.
template <bool kFaint, bool kNested>
void ScanPixel(const std::uint8_t* p, int x, int y, const RedTable& red, const RedTable* faint,
               RunTracker* red_runs, RunTracker* faint_runs) {
  const int b = p[0], g = p[1], r = p[2];
  if constexpr (kFaint) {
    const bool faint_red = faint->isRed(r, g, b);
    faint_runs->step(faint_red, y, x);
    red_runs->step((!kNested || faint_red) && red.isRed(r, g, b), y, x);
  } else {
    red_runs->step(red.isRed(r, g, b), y, x);
  }
}

// One row. Sixteen pixels at a time are first tested against the least red lead of the tables
// in use (4 (R − G) + (B − G), see RedTable): where none reaches it, none is red at any level,
// and their lookups are skipped. On the load scenes that is half of all such blocks. kMinChannel:
// also min(R, G, B) into `row_min`, from the channels loaded here (a second pass over the row to
// separate them again cost up to 0.3 ms a frame).
template <bool kFaint, bool kNested, bool kMinChannel>
void ScanRow(const std::uint8_t* row, int cols, int y, const RedTable& red, const RedTable* faint,
             RunTracker* red_runs, RunTracker* faint_runs, std::uint8_t* row_min) {
  int x = 0;
#if CV_SIMD128
  int least_lead = red.leastRedLead();
  if constexpr (kFaint) least_lead = std::min(least_lead, faint->leastRedLead());
  const cv::v_int16x8 least =
      cv::v_setall_s16(static_cast<std::int16_t>(std::min(least_lead, 2048)));
  for (; x + 16 <= cols; x += 16) {
    const std::uint8_t* p = row + 3 * static_cast<std::ptrdiff_t>(x);
    cv::v_uint8x16 b, g, r;
    cv::v_load_deinterleave(p, b, g, r);
    if constexpr (kMinChannel) cv::v_store(row_min + x, cv::v_min(cv::v_min(b, g), r));
    cv::v_uint16x8 b0, b1, g0, g1, r0, r1;
    cv::v_expand(b, b0, b1);
    cv::v_expand(g, g0, g1);
    cv::v_expand(r, r0, r1);
    // 4 R + B − 5 G lies in −1275 … 1275.
    const cv::v_int16x8 lead0 =
        cv::v_reinterpret_as_s16((r0 << 2) + b0) - cv::v_reinterpret_as_s16((g0 << 2) + g0);
    const cv::v_int16x8 lead1 =
        cv::v_reinterpret_as_s16((r1 << 2) + b1) - cv::v_reinterpret_as_s16((g1 << 2) + g1);
    if (!cv::v_check_any((lead0 >= least) | (lead1 >= least))) {
      red_runs->step(false, y, x);
      if constexpr (kFaint) faint_runs->step(false, y, x);
      continue;
    }
    for (int k = 0; k < 16; ++k) {
      ScanPixel<kFaint, kNested>(p + 3 * static_cast<std::ptrdiff_t>(k), x + k, y, red, faint,
                                 red_runs, faint_runs);
    }
  }
#endif
  if constexpr (kMinChannel) {
    MinChannelRow(row + 3 * static_cast<std::ptrdiff_t>(x), cols - x, row_min + x);
  }
  for (; x < cols; ++x) {
    ScanPixel<kFaint, kNested>(row + 3 * static_cast<std::ptrdiff_t>(x), x, y, red, faint, red_runs,
                               faint_runs);
  }
  red_runs->finish(y, cols);
  if constexpr (kFaint) faint_runs->finish(y, cols);
}

// Each output pixel the mean of a 2 × 2 block of the two rows, rounded down.
void HalveRows(const std::uint8_t* upper, const std::uint8_t* lower, std::ptrdiff_t half_cols,
               std::uint8_t* out) {
  std::ptrdiff_t x = 0;
#if CV_SIMD128
  for (; x + 16 <= half_cols; x += 16) {
    cv::v_uint8x16 ue, uo, le, lo;
    cv::v_load_deinterleave(upper + 2 * x, ue, uo);
    cv::v_load_deinterleave(lower + 2 * x, le, lo);
    cv::v_uint16x8 a0, a1, b0, b1, c0, c1, d0, d1;
    cv::v_expand(ue, a0, a1);
    cv::v_expand(uo, b0, b1);
    cv::v_expand(le, c0, c1);
    cv::v_expand(lo, d0, d1);
    cv::v_store(out + x, cv::v_pack((a0 + b0 + c0 + d0) >> 2, (a1 + b1 + c1 + d1) >> 2));
  }
#endif
  for (; x < half_cols; ++x) {
    const int sum = upper[2 * x] + upper[2 * x + 1] + lower[2 * x] + lower[2 * x + 1];
    out[x] = static_cast<std::uint8_t>(sum >> 2);
  }
}

// kMinChannel: min(R, G, B) into scan->min_channel, and halved into scan->dark_half when that is
// allocated.
template <bool kFaint, bool kNested, bool kMinChannel>
void ScanRows(const cv::Mat& bgr, const RedTable& red, const RedTable* faint, FrameScan* scan) {
  RunTracker red_runs(&scan->red.runs), faint_runs(&scan->faint.runs);
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
    std::uint8_t* row_min = kMinChannel ? scan->min_channel.ptr<std::uint8_t>(y) : nullptr;
    ScanRow<kFaint, kNested, kMinChannel>(row, bgr.cols, y, red, faint, &red_runs, &faint_runs,
                                          row_min);
    if constexpr (kMinChannel) {
      if (y % 2 == 1 && y / 2 < scan->dark_half.rows) {
        HalveRows(scan->min_channel.ptr<std::uint8_t>(y - 1), row_min, scan->dark_half.cols,
                  scan->dark_half.ptr<std::uint8_t>(y / 2));
      }
    }
  }
}

}  // namespace

FrameScan ScanFrame(const cv::Mat& bgr, const FrameScanRequest& request) {
  CV_Assert(bgr.type() == CV_8UC3);
  FrameScan scan;
  scan.red.size = bgr.size();
  const RedTable& red = RedTable::For(request.red);
  const RedTable* faint = nullptr;
  if (request.faint) {
    scan.faint.size = bgr.size();
    faint = &RedTable::For(*request.faint);
  }
  // The half-resolution image is made from the full one's rows, so asking for it keeps that too.
  const bool dark = request.min_channel || request.dark_half;
  if (dark) scan.min_channel.create(bgr.size(), CV_8U);
  if (request.dark_half) scan.dark_half.create(bgr.rows / 2, bgr.cols / 2, CV_8U);
  const bool nested = request.faint && request.faint->min_a <= request.red.min_a &&
                      request.faint->min_b <= request.red.min_b;
  if (faint == nullptr) {
    dark ? ScanRows<false, false, true>(bgr, red, faint, &scan)
         : ScanRows<false, false, false>(bgr, red, faint, &scan);
  } else if (nested) {
    dark ? ScanRows<true, true, true>(bgr, red, faint, &scan)
         : ScanRows<true, true, false>(bgr, red, faint, &scan);
  } else {
    dark ? ScanRows<true, false, true>(bgr, red, faint, &scan)
         : ScanRows<true, false, false>(bgr, red, faint, &scan);
  }
  return scan;
}

}  // namespace pintag::stage
