#pragma once
// The label's type: text shaped with Pango (so Devanagari, Tamil and the other Indian scripts get
// their conjuncts and vowel signs), in DejaVu Sans with a Noto face for each script DejaVu lacks,
// measured and drawn in the cairo context's user units (mm on labels).

#include <cairo.h>

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace pintag::label {

/// A line's size at a font size, in user units. The ink box is relative to the pen position on
/// the baseline (y down, so the top of the ink is at a negative y).
struct TextExtents {
  double advance = 0;
  double ink_x = 0;
  double ink_y = 0;
  double ink_width = 0;
  double ink_height = 0;
};

/// Shapes, measures and draws single lines on one cairo context. Hinting and glyph rounding are
/// off, so advances scale linearly with the size and a line fits alike in PDF, SVG and PNG. Make
/// one per page after the context's transformation is set.
class LabelFont {
 public:
  explicit LabelFont(cairo_t* cr);
  ~LabelFont();
  LabelFont(const LabelFont&) = delete;
  LabelFont& operator=(const LabelFont&) = delete;

  TextExtents measure(std::string_view text, bool bold, double size);
  /// Advance at font size 1 (measured at a larger size, where rounding is negligible).
  double advancePerSize(std::string_view text, bool bold);
  /// Draws `text` with the start of its baseline at (x, baseline).
  void show(std::string_view text, bool bold, double size, double x, double baseline);
  /// Byte offsets where a line may be cut without splitting a character as it is read (a letter
  /// and its vowel signs, a conjunct, a base and its combining marks): 0, …, text.size().
  std::vector<std::size_t> cutPoints(std::string_view text);
  /// The family of the face each run of `text` is set in, in order (one entry per run): what a
  /// line will print in, for checking that a script gets its own face.
  std::vector<std::string> familiesOf(std::string_view text, bool bold);

  cairo_t* context() const { return cr_; }

 private:
  struct Pango;
  cairo_t* cr_;
  std::unique_ptr<Pango> pango_;
};

}  // namespace pintag::label
