#include "label/label_text.hpp"

#include <algorithm>
#include <vector>

#include "pintag/codec/utf8.hpp"

namespace pintag::label {
namespace {

constexpr char32_t kReplacement = 0xFFFD;

// A line's ink band, in font sizes from its baseline and beyond the ends of its width. Noto's
// Indian faces reach about 1.1 above and 0.5 below; stacked marks beyond that are cut.
constexpr double kBandAbove = 1.3;
constexpr double kBandBelow = 0.6;
constexpr double kBandSide = 0.3;

bool IsContinuation(char byte) {
  return (static_cast<unsigned char>(byte) & 0xC0) == 0x80;
}

// The code point at text[i], advancing i past it. Invalid bytes yield one U+FFFD for the bad byte
// and the continuation bytes right after it, so an overlong or surrogate sequence is one mark.
char32_t Next(std::string_view text, std::size_t& i) {
  const Utf8CodePoint decoded = DecodeUtf8(text, i);
  if (decoded.length > 0) {
    i += decoded.length;
    return decoded.value;
  }
  ++i;
  while (i < text.size() && IsContinuation(text[i])) ++i;
  return kReplacement;
}

bool IsSpace(char32_t c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == 0xA0 || c == 0x2007 ||
         c == 0x202F || c == 0x3000;
}

bool IsControl(char32_t c) {
  return c < 0x20 || (c >= 0x7F && c < 0xA0) || c == 0x2028 || c == 0x2029 ||
         (c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069) || c == 0xFEFF;
}

}  // namespace

std::string SanitizeUtf8(std::string_view text, bool* cut) {
  std::string out;
  out.reserve(text.size());
  std::size_t count = 0;
  bool pending_space = false;
  bool dropped = false;  // a code point that would print was left out for the limit
  for (std::size_t i = 0; i < text.size();) {
    const char32_t c = Next(text, i);
    if (IsSpace(c)) {
      pending_space = !out.empty();
      continue;
    }
    if (IsControl(c)) continue;
    if (count + (pending_space ? 2 : 1) > kMaxDrawnCodePoints) {
      dropped = true;
      break;
    }
    if (pending_space) {
      out += ' ';
      ++count;
      pending_space = false;
    }
    AppendUtf8(out, c);
    ++count;
  }
  if (cut != nullptr) *cut = dropped;
  return out;
}

DrawnLine DrawLine(LabelFont& font, std::string_view text, double x, double width, double baseline,
                   const LineStyle& style) {
  std::string line(text);
  double size = style.size;
  double advance = font.measure(line, style.bold, size).advance;
  if (advance > width && advance > 0) {
    // Advances scale linearly with the size (hinting is off), so one step suffices.
    size = std::max(style.min_size, style.size * width / advance * 0.999);
    advance = font.measure(line, style.bold, size).advance;
  }
  const bool cut = advance > width;
  if (cut) {
    // Still too wide at the smallest size: keep the most characters that fit with an ellipsis,
    // all from the start, or half from each end.
    const std::vector<std::size_t> at = font.cutPoints(line);
    const std::size_t characters = at.size() - 1;
    std::size_t first = 0;  // the first character that may be cut
    while (first < characters && at[first] < style.uncut_prefix) ++first;
    const auto kept = [&](std::size_t count) {
      const std::size_t from_end = style.cut_middle ? count / 2 : 0;
      std::string head = line.substr(0, at[first + count - from_end]);
      while (head.size() > style.uncut_prefix && (head.back() == ' ' || head.back() == ',')) {
        head.pop_back();
      }
      std::string tail = line.substr(at[characters - from_end]);
      while (!tail.empty() && tail.front() == ' ') tail.erase(0, 1);
      return head + "\u2026" + tail;
    };
    std::size_t lo = 0;
    std::size_t hi = characters - first;
    while (lo < hi) {
      const std::size_t mid = (lo + hi + 1) / 2;
      if (font.measure(kept(mid), style.bold, size).advance <= width) {
        lo = mid;
      } else {
        hi = mid - 1;
      }
    }
    line = kept(lo);
    advance = font.measure(line, style.bold, size).advance;
  }
  double left = x;
  if (style.align == Align::kCentre) left = x + (width - advance) / 2;
  if (style.align == Align::kRight) left = x + width - advance;
  double clip_left = x - kBandSide * size;
  double clip_right = x + width + kBandSide * size;
  double clip_top = baseline - kBandAbove * size;
  double clip_bottom = baseline + kBandBelow * size;
  if (style.within != nullptr) {
    clip_left = std::max(clip_left, style.within->x);
    clip_right = std::min(clip_right, style.within->right());
    clip_top = std::max(clip_top, style.within->y);
    clip_bottom = std::min(clip_bottom, style.within->bottom());
  }
  cairo_t* cr = font.context();
  cairo_save(cr);
  cairo_rectangle(cr, clip_left, clip_top, std::max(0.0, clip_right - clip_left),
                  std::max(0.0, clip_bottom - clip_top));
  cairo_clip(cr);
  font.show(line, style.bold, size, left, baseline);
  cairo_restore(cr);
  return {size, cut};
}

}  // namespace pintag::label
