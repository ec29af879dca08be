#include "candidates/frame_scan.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <map>
#include <mutex>
#include <opencv2/core/hal/intrin.hpp>
#include <utility>
#include <vector>

#include "candidates/quads.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define PINTAG_GATHER_RED_LOOKUPS 1
#else
#define PINTAG_GATHER_RED_LOOKUPS 0
#endif

namespace pintag::stage {
namespace {

// Runs of one redness level along a row, fed one pixel or a block of 16 at a time.
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
  /// Pixels x … x + 15: bit k of `mask` is pixel x + k. Only where the level changes is work done.
  void block(unsigned mask, int y, int x) {
    const unsigned inside = start_ >= 0 ? 1U : 0U;
    for (unsigned edges = (mask ^ ((mask << 1U) | inside)) & 0xFFFFU; edges != 0;
         edges &= edges - 1) {
      const int k = std::countr_zero(edges);
      if ((mask >> static_cast<unsigned>(k)) & 1U) {
        start_ = x + k;
      } else {
        out_->push_back({y, start_, x + k - 1});
        start_ = -1;
      }
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

// The row's full blocks of 16 pixels as bit masks of each level (bit k: pixel 16 i + k of block
// i). Each block is first tested against the least red lead of the tables in use, 4 (R − G) +
// (B − G) (see RedTable): where no pixel reaches it, none is red at any level and nothing is looked
// up. On the load scenes that is half of all blocks; a quarter of all pixels are faint-red (warm
// photographs), so the lookups of the other half are the scan's main cost. kMinChannel: also
// min(R, G, B) into `row_min`, from the channels loaded here (a second pass over the row to
// separate them again cost up to 0.3 ms a frame).
struct RowMasks {
  const RedTable& red;
  const RedTable* faint;  // null: no faint level
  int least_lead;         // the least lead of either level, capped to fit 16 bits
  std::uint16_t* red_masks;
  std::uint16_t* faint_masks;
  std::uint8_t* row_min;
  const std::vector<std::uint32_t>* paired;  // for gathers: PairedTable(red, faint or red)
};

// One table read per pixel of a block that passes.
template <bool kFaint, bool kNested, bool kMinChannel>
void MaskBlocksOneByOne(const std::uint8_t* row, int blocks, const RowMasks& m) {
#if CV_SIMD128
  const cv::v_int16x8 least = cv::v_setall_s16(static_cast<std::int16_t>(m.least_lead));
  for (int i = 0; i < blocks; ++i) {
    const std::uint8_t* p = row + 48 * static_cast<std::ptrdiff_t>(i);
    cv::v_uint8x16 b, g, r;
    cv::v_load_deinterleave(p, b, g, r);
    if constexpr (kMinChannel)
      cv::v_store(m.row_min + 16 * static_cast<std::ptrdiff_t>(i), cv::v_min(cv::v_min(b, g), r));
    cv::v_uint16x8 b0, b1, g0, g1, r0, r1;
    cv::v_expand(b, b0, b1);
    cv::v_expand(g, g0, g1);
    cv::v_expand(r, r0, r1);
    // 4 R + B − 5 G lies in −1275 … 1275.
    const cv::v_int16x8 lead0 =
        cv::v_reinterpret_as_s16((r0 << 2) + b0) - cv::v_reinterpret_as_s16((g0 << 2) + g0);
    const cv::v_int16x8 lead1 =
        cv::v_reinterpret_as_s16((r1 << 2) + b1) - cv::v_reinterpret_as_s16((g1 << 2) + g1);
    unsigned red_mask = 0, faint_mask = 0;
    if (cv::v_check_any((lead0 >= least) | (lead1 >= least))) {
      for (int k = 0; k < 16; ++k) {
        const std::uint8_t* q = p + 3 * static_cast<std::ptrdiff_t>(k);
        const int qb = q[0], qg = q[1], qr = q[2];
        if constexpr (kFaint) {
          const bool faint_red = m.faint->isRed(qr, qg, qb);
          faint_mask |= static_cast<unsigned>(faint_red) << static_cast<unsigned>(k);
          red_mask |= static_cast<unsigned>((!kNested || faint_red) && m.red.isRed(qr, qg, qb))
                      << static_cast<unsigned>(k);
        } else {
          red_mask |= static_cast<unsigned>(m.red.isRed(qr, qg, qb)) << static_cast<unsigned>(k);
        }
      }
    }
    m.red_masks[i] = static_cast<std::uint16_t>(red_mask);
    if constexpr (kFaint) m.faint_masks[i] = static_cast<std::uint16_t>(faint_mask);
  }
#else
  static_cast<void>(row), static_cast<void>(blocks), static_cast<void>(m);
#endif
}

#if PINTAG_GATHER_RED_LOOKUPS
// Both levels' least red R in one entry (main in the low 16 bits, faint in the high), by
// (G << 8) | B: one gather serves both levels. Built once per pair of tables (they live as long as
// the process); a scan of the main level alone pairs its table with itself.
const std::vector<std::uint32_t>& PairedTable(const RedTable& main, const RedTable& faint) {
  static std::mutex mutex;
  static std::map<std::pair<const RedTable*, const RedTable*>, std::vector<std::uint32_t>> tables;
  const std::lock_guard<std::mutex> lock(mutex);
  std::vector<std::uint32_t>& table = tables[{&main, &faint}];
  if (table.empty()) {
    table.resize(std::size_t{1} << 16U);
    for (std::size_t i = 0; i < table.size(); ++i) {
      table[i] = main.leastRedR()[i] | (std::uint32_t{faint.leastRedR()[i]} << 16U);
    }
  }
  return table;
}

// Bit k set where pixel k's R (16 lanes of `r`) is below its least red R, given for pixels 0–7 in
// `lo` and 8–15 in `hi` (32-bit lanes).
__attribute__((target("avx2"))) inline unsigned BelowBits(__m256i r, __m256i lo, __m256i hi) {
  // packus interleaves the 128-bit halves (lo 0–3, hi 0–3, lo 4–7, hi 4–7): put them in order.
  const __m256i least = _mm256_permute4x64_epi64(_mm256_packus_epi32(lo, hi), 0xD8);
  const __m256i below = _mm256_cmpgt_epi16(least, r);
  return static_cast<unsigned>(_mm_movemask_epi8(
      _mm_packs_epi16(_mm256_castsi256_si128(below), _mm256_extracti128_si256(below, 1))));
}

// The same masks with the 16 pixels' table entries gathered at once. It repeats the block loop of
// MaskBlocksOneByOne rather than sharing it: a target("avx2") function cannot be inlined into one
// built for plain x86-64, and a call per block would cost more than the loop.
template <bool kFaint, bool kMinChannel>
__attribute__((target("avx2"))) void MaskBlocksGathered(const std::uint8_t* row, int blocks,
                                                        const RowMasks& m) {
  const __m256i least = _mm256_set1_epi16(static_cast<std::int16_t>(m.least_lead - 1));
  const __m256i low16 = _mm256_set1_epi32(0xFFFF);
  const auto* table = reinterpret_cast<const int*>(m.paired->data());
  for (int i = 0; i < blocks; ++i) {
    cv::v_uint8x16 b8, g8, r8;
    cv::v_load_deinterleave(row + 48 * static_cast<std::ptrdiff_t>(i), b8, g8, r8);
    if constexpr (kMinChannel) {
      cv::v_store(m.row_min + 16 * static_cast<std::ptrdiff_t>(i),
                  cv::v_min(cv::v_min(b8, g8), r8));
    }
    const __m256i b = _mm256_cvtepu8_epi16(b8.val);
    const __m256i g = _mm256_cvtepu8_epi16(g8.val);
    const __m256i r = _mm256_cvtepu8_epi16(r8.val);
    const __m256i lead = _mm256_sub_epi16(_mm256_add_epi16(_mm256_slli_epi16(r, 2), b),
                                          _mm256_add_epi16(_mm256_slli_epi16(g, 2), g));
    const __m256i passes = _mm256_cmpgt_epi16(lead, least);
    unsigned red_mask = 0, faint_mask = 0;
    if (!_mm256_testz_si256(passes, passes)) {
      const __m256i index = _mm256_or_si256(_mm256_slli_epi16(g, 8), b);
      const __m256i lo =
          _mm256_i32gather_epi32(table, _mm256_cvtepu16_epi32(_mm256_castsi256_si128(index)), 4);
      const __m256i hi = _mm256_i32gather_epi32(
          table, _mm256_cvtepu16_epi32(_mm256_extracti128_si256(index, 1)), 4);
      red_mask = ~BelowBits(r, _mm256_and_si256(lo, low16), _mm256_and_si256(hi, low16)) & 0xFFFFU;
      if constexpr (kFaint) {
        faint_mask = ~BelowBits(r, _mm256_srli_epi32(lo, 16), _mm256_srli_epi32(hi, 16)) & 0xFFFFU;
      }
    }
    m.red_masks[i] = static_cast<std::uint16_t>(red_mask);
    if constexpr (kFaint) m.faint_masks[i] = static_cast<std::uint16_t>(faint_mask);
  }
}

#endif

// One row: its full blocks by masks, then the pixels left over one at a time.
template <bool kFaint, bool kNested, bool kMinChannel>
void ScanRow(const std::uint8_t* row, int cols, int y, bool gather, const RowMasks& masks,
             RunTracker* red_runs, RunTracker* faint_runs) {
  const int blocks = CV_SIMD128 ? cols / 16 : 0;
#if PINTAG_GATHER_RED_LOOKUPS
  if (gather) {
    MaskBlocksGathered<kFaint, kMinChannel>(row, blocks, masks);
  } else {
    MaskBlocksOneByOne<kFaint, kNested, kMinChannel>(row, blocks, masks);
  }
#else
  static_cast<void>(gather);
  MaskBlocksOneByOne<kFaint, kNested, kMinChannel>(row, blocks, masks);
#endif
  for (int i = 0; i < blocks; ++i) {
    red_runs->block(masks.red_masks[i], y, 16 * i);
    if constexpr (kFaint) faint_runs->block(masks.faint_masks[i], y, 16 * i);
  }
  const int x = 16 * blocks;
  if constexpr (kMinChannel) {
    MinChannelRow(row + 3 * static_cast<std::ptrdiff_t>(x), cols - x, masks.row_min + x);
  }
  for (int tail = x; tail < cols; ++tail) {
    ScanPixel<kFaint, kNested>(row + 3 * static_cast<std::ptrdiff_t>(tail), tail, y, masks.red,
                               masks.faint, red_runs, faint_runs);
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
void ScanRows(const cv::Mat& bgr, const RedTable& red, const RedTable* faint, bool gather,
              FrameScan* scan) {
  RunTracker red_runs(&scan->red.runs), faint_runs(&scan->faint.runs);
  int least_lead = red.leastRedLead();
  if constexpr (kFaint) least_lead = std::min(least_lead, faint->leastRedLead());
  std::vector<std::uint16_t> red_masks(static_cast<std::size_t>(bgr.cols / 16));
  std::vector<std::uint16_t> faint_masks(kFaint ? red_masks.size() : 0);
  RowMasks masks{red,     faint,  std::min(least_lead, 2048), red_masks.data(), faint_masks.data(),
                 nullptr, nullptr};
#if PINTAG_GATHER_RED_LOOKUPS
  if (gather) masks.paired = &PairedTable(red, kFaint ? *faint : red);
#endif
  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
    std::uint8_t* row_min = kMinChannel ? scan->min_channel.ptr<std::uint8_t>(y) : nullptr;
    masks.row_min = row_min;
    ScanRow<kFaint, kNested, kMinChannel>(row, bgr.cols, y, gather, masks, &red_runs, &faint_runs);
    if constexpr (kMinChannel) {
      if (y % 2 == 1 && y / 2 < scan->dark_half.rows) {
        HalveRows(scan->min_channel.ptr<std::uint8_t>(y - 1), row_min, scan->dark_half.cols,
                  scan->dark_half.ptr<std::uint8_t>(y / 2));
      }
    }
  }
}

}  // namespace

bool GathersRedLookups() {
#if PINTAG_GATHER_RED_LOOKUPS
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

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
  const bool gather = request.lookups == RedLookups::kFastest && GathersRedLookups();
  if (faint == nullptr) {
    dark ? ScanRows<false, false, true>(bgr, red, faint, gather, &scan)
         : ScanRows<false, false, false>(bgr, red, faint, gather, &scan);
  } else if (nested) {
    dark ? ScanRows<true, true, true>(bgr, red, faint, gather, &scan)
         : ScanRows<true, true, false>(bgr, red, faint, gather, &scan);
  } else {
    dark ? ScanRows<true, false, true>(bgr, red, faint, gather, &scan)
         : ScanRows<true, false, false>(bgr, red, faint, gather, &scan);
  }
  return scan;
}

}  // namespace pintag::stage
