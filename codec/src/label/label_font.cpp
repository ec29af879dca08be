#include "label/label_font.hpp"

#include <pango/pangocairo.h>

#include <string>
#include <utility>
#include <vector>

namespace pintag::label {
namespace {

// DejaVu Sans first (Latin, digits, Greek, Cyrillic, the "…"), then a face for each script of
// India's official languages it lacks; fontconfig's own fallback comes after these.
constexpr const char* kFamilies =
    "DejaVu Sans,Noto Sans Devanagari,Noto Sans Bengali,Noto Sans Gurmukhi,Noto Sans Gujarati,"
    "Noto Sans Oriya,Noto Sans Tamil,Noto Sans Telugu,Noto Sans Kannada,Noto Sans Malayalam,"
    "Noto Sans Ol Chiki,Noto Sans Meetei Mayek,Noto Naskh Arabic";

// Urdu's face. DejaVu Sans covers most of the Arabic block but not ہ (U+06C1) or ے (U+06D2), so
// an Urdu word came out in two faces, its heavy DejaVu letters beside thin Naskh ones.
constexpr const char* kArabicFamily = "Noto Naskh Arabic";

/// Byte ranges of `text` in the Arabic script, each with the spaces and punctuation between its
/// words (whatever belongs to no script) and the marks on its letters (harakat, which inherit
/// their letter's script), so that a phrase is set in one face.
std::vector<std::pair<std::size_t, std::size_t>> ArabicRuns(std::string_view text) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  // No run open: npos (a std::optional here drew GCC 12's false -Wmaybe-uninitialized).
  constexpr std::size_t kNoRun = std::string_view::npos;
  std::size_t start = kNoRun;
  std::size_t last_end = 0;  // the end of the run's last Arabic character
  for (std::size_t at = 0; at < text.size();) {
    const char* here = text.data() + at;
    const gunichar c = g_utf8_get_char_validated(here, static_cast<gssize>(text.size() - at));
    const std::size_t next =
        c >= 0xFFFFFFFE ? at + 1 : static_cast<std::size_t>(g_utf8_next_char(here) - text.data());
    const GUnicodeScript script =
        c >= 0xFFFFFFFE ? G_UNICODE_SCRIPT_UNKNOWN : g_unichar_get_script(c);
    if (script == G_UNICODE_SCRIPT_ARABIC) {
      if (start == kNoRun) start = at;
      last_end = next;
    } else if (script == G_UNICODE_SCRIPT_INHERITED && start != kNoRun && last_end == at) {
      last_end = next;  // a mark on the run's last letter
    } else if (script != G_UNICODE_SCRIPT_COMMON && script != G_UNICODE_SCRIPT_INHERITED &&
               start != kNoRun) {
      runs.emplace_back(start, last_end);
      start = kNoRun;
    }
    at = next;
  }
  if (start != kNoRun) runs.emplace_back(start, last_end);
  return runs;
}

// Advances are measured at this size and scaled: Pango's units are 1/1024 of a user unit.
constexpr double kMeasureSize = 16.0;

// The Brahmic scripts whose virama joins the next consonant into a conjunct (Unicode's GB9c):
// Devanagari, Bengali, Gurmukhi, Gujarati, Oriya, Telugu, Kannada and Malayalam, each a block of
// 128 with the virama at +0x4D. Tamil's pulli (U+0BCD) is left out: Tamil writes a dead consonant
// and the next one apart, so a cut there splits nothing.
constexpr gunichar kConjunctBlocks[] = {0x0900, 0x0980, 0x0A00, 0x0A80,
                                        0x0B00, 0x0C00, 0x0C80, 0x0D00};

// The block of `c` when it is one of those scripts' viramas, else 0.
gunichar ViramaBlock(gunichar c) {
  for (const gunichar block : kConjunctBlocks) {
    if (c == block + 0x4D) return block;
  }
  return 0;
}

// A consonant of the block starting at `block`: the letters KA … HA, and the nukta forms at
// +0x58 … +0x5F (Devanagari's QA … YYA, Bengali's RRA … YYA, Oriya's RRA … YYA).
bool IsConsonantOf(gunichar c, gunichar block) {
  if (c < block || c >= block + 0x80) return false;
  const gunichar offset = c - block;
  const bool consonant = (offset >= 0x15 && offset <= 0x39) || (offset >= 0x58 && offset <= 0x5F);
  return consonant && g_unichar_type(c) == G_UNICODE_OTHER_LETTER;
}

}  // namespace

struct LabelFont::Pango {
  PangoContext* context = nullptr;
  PangoLayout* layout = nullptr;
  PangoFontDescription* description = nullptr;

  ~Pango() {
    if (description) pango_font_description_free(description);
    if (layout) g_object_unref(layout);
    if (context) g_object_unref(context);
  }

  void set(std::string_view text, bool bold, double size) {
    pango_font_description_set_weight(description, bold ? PANGO_WEIGHT_BOLD : PANGO_WEIGHT_NORMAL);
    pango_font_description_set_absolute_size(description, size * PANGO_SCALE);
    pango_layout_set_font_description(layout, description);
    pango_layout_set_text(layout, text.data(), static_cast<int>(text.size()));
    PangoAttrList* attributes = nullptr;
    for (const auto& [begin, end] : ArabicRuns(text)) {
      if (attributes == nullptr) attributes = pango_attr_list_new();
      PangoAttribute* family = pango_attr_family_new(kArabicFamily);
      family->start_index = static_cast<guint>(begin);
      family->end_index = static_cast<guint>(end);
      pango_attr_list_insert(attributes, family);  // the list owns it now
    }
    pango_layout_set_attributes(layout, attributes);
    if (attributes != nullptr) pango_attr_list_unref(attributes);
  }
};

LabelFont::LabelFont(cairo_t* cr) : cr_(cr), pango_(std::make_unique<Pango>()) {
  pango_->context = pango_cairo_create_context(cr);
  cairo_font_options_t* options = cairo_font_options_create();
  cairo_font_options_set_hint_metrics(options, CAIRO_HINT_METRICS_OFF);
  cairo_font_options_set_hint_style(options, CAIRO_HINT_STYLE_NONE);
  cairo_font_options_set_antialias(options, CAIRO_ANTIALIAS_GRAY);
  pango_cairo_context_set_font_options(pango_->context, options);
  cairo_font_options_destroy(options);
  pango_context_set_round_glyph_positions(pango_->context, FALSE);
  pango_->layout = pango_layout_new(pango_->context);
  pango_layout_set_single_paragraph_mode(pango_->layout, TRUE);
  pango_->description = pango_font_description_new();
  pango_font_description_set_family(pango_->description, kFamilies);
}

LabelFont::~LabelFont() = default;

TextExtents LabelFont::measure(std::string_view text, bool bold, double size) {
  pango_->set(text, bold, size);
  PangoRectangle ink;
  PangoRectangle logical;
  pango_layout_get_extents(pango_->layout, &ink, &logical);
  const double baseline = pango_layout_get_baseline(pango_->layout);
  TextExtents extents;
  extents.advance = logical.width / static_cast<double>(PANGO_SCALE);
  extents.ink_x = ink.x / static_cast<double>(PANGO_SCALE);
  extents.ink_y = (ink.y - baseline) / static_cast<double>(PANGO_SCALE);
  extents.ink_width = ink.width / static_cast<double>(PANGO_SCALE);
  extents.ink_height = ink.height / static_cast<double>(PANGO_SCALE);
  return extents;
}

double LabelFont::advancePerSize(std::string_view text, bool bold) {
  return measure(text, bold, kMeasureSize).advance / kMeasureSize;
}

void LabelFont::show(std::string_view text, bool bold, double size, double x, double baseline) {
  pango_->set(text, bold, size);
  const double above = pango_layout_get_baseline(pango_->layout) / static_cast<double>(PANGO_SCALE);
  cairo_move_to(cr_, x, baseline - above);
  pango_cairo_show_layout(cr_, pango_->layout);
}

std::vector<std::string> LabelFont::familiesOf(std::string_view text, bool bold) {
  pango_->set(text, bold, kMeasureSize);
  std::vector<std::string> families;
  PangoLayoutIter* iter = pango_layout_get_iter(pango_->layout);
  do {
    const PangoLayoutRun* run = pango_layout_iter_get_run_readonly(iter);
    if (run == nullptr) continue;  // the end of the line
    PangoFontDescription* face = pango_font_describe(run->item->analysis.font);
    families.emplace_back(pango_font_description_get_family(face));
    pango_font_description_free(face);
  } while (pango_layout_iter_next_run(iter));
  pango_layout_iter_free(iter);
  return families;
}

std::vector<std::size_t> LabelFont::cutPoints(std::string_view text) {
  pango_layout_set_text(pango_->layout, text.data(), static_cast<int>(text.size()));
  pango_layout_set_attributes(pango_->layout, nullptr);  // the last text's runs are not this one's
  int count = 0;
  const PangoLogAttr* attrs = pango_layout_get_log_attrs_readonly(pango_->layout, &count);
  // attrs[i] describes the position before the i-th character (count = characters + 1).
  // Pango 1.50 puts a cursor position after a virama ("क्|ष", "स्|त्|र"): a line cut there ends
  // in a visible halant and the conjunct is lost, so such positions are not cuts here.
  std::vector<std::size_t> cuts;
  std::size_t byte = 0;
  gunichar virama_block = 0;  // the block of the virama just passed, through any ZWJ or ZWNJ
  for (int i = 0; i < count; ++i) {
    const gunichar c = byte < text.size() ? g_utf8_get_char(text.data() + byte) : 0;
    const bool joins = virama_block != 0 && IsConsonantOf(c, virama_block);
    if (i == 0 || i == count - 1 || (attrs[i].is_cursor_position && !joins)) cuts.push_back(byte);
    if (byte < text.size()) {
      if (c != 0x200C && c != 0x200D) virama_block = ViramaBlock(c);
      byte = static_cast<std::size_t>(g_utf8_next_char(text.data() + byte) - text.data());
    }
  }
  if (cuts.empty() || cuts.back() != text.size()) cuts.push_back(text.size());
  return cuts;
}

}  // namespace pintag::label
