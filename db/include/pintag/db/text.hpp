#pragma once
// What text the registry accepts. Quotes, SQL, any language: stored and returned verbatim (every
// query binds parameters). NUL and other control characters, invalid UTF-8 and over-long text:
// rejected with kInvalid, naming the field.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "pintag/db/result.hpp"

namespace pintag::db {

inline constexpr std::size_t kMaxNameBytes = 200;      ///< office, district, state, ... names
inline constexpr std::size_t kMaxLabelBytes = 200;     ///< token labels, plan descriptions
inline constexpr std::size_t kMaxBinBytes = 64;        ///< sort plan and bin names
inline constexpr std::size_t kMaxJsonBytes = 1 << 20;  ///< a scan log entry's JSON text

/// `text` without the spaces at either end (tabs and inner spaces kept): how names are compared
/// and, from the seed and imports, stored ("New Delhi " and "New Delhi" are one office).
std::string_view TrimSpaces(std::string_view text);

/// `text` without tabs and Unicode spaces at either end: the space separators (Zs: U+0020, U+00A0
/// no-break space, U+1680, U+2000–U+200A, U+202F, U+205F, U+3000) and the zero-width spaces
/// U+200B, U+2060 and U+FEFF, all of them blank to IsBlank. How the importer trims a CSV field, so
/// a field of nothing else trims to "". Joiners, variation selectors and bidi controls stay: at
/// an end they still belong to the visible text beside them.
std::string_view TrimUnicodeSpaces(std::string_view text);

/// True when `text` shows nothing: it is empty or holds only spaces and invisible characters —
/// Unicode's space separators (Zs: U+0020, U+00A0 no-break space, U+2000–U+200A, U+3000, …),
/// line and paragraph separators, format characters (Cf: U+200B zero-width space, U+200C/D,
/// U+2060 word joiner, U+FEFF, U+00AD soft hyphen, bidi controls, …), U+0085, the Hangul fillers
/// and variation selectors. Invalid UTF-8 is not blank (CheckText refuses it on its own).
bool IsBlank(std::string_view text);

/// Nothing when `value` is acceptable for `field`; else the kInvalid error saying why: longer than
/// `max_bytes`, invalid UTF-8, a control character (C0, DEL, C1), U+2028/U+2029, or a bidi
/// embedding, override or isolate (U+202A–U+202E, U+2066–U+2069). Unless `allow_empty`, a blank
/// value (IsBlank) is refused too.
std::optional<Error> CheckText(std::string_view field, std::string_view value,
                               std::size_t max_bytes, bool allow_empty = false);

/// CheckText for text that is looked for, not stored (a search's name prefix, district, state):
/// the same length, control-character and UTF-8 checks, but not RefusedCodePoint's, so a value
/// stored before those were refused can still be searched for.
std::optional<Error> CheckQueryText(std::string_view field, std::string_view value,
                                    std::size_t max_bytes);

/// What CheckText refuses in stored text beyond the C0 controls and DEL, named for a message, or
/// nothing: the C1 controls (a terminal takes U+009B as an escape), the line and paragraph
/// separators (a line break in a one-line name), and the bidi embeddings, overrides and isolates,
/// which reorder the text after them ("Evil" + U+202E + "ecilop" shows as "Evilpolice"). The
/// marks U+200E and U+200F are not among them: Urdu text needs them.
const char* RefusedCodePoint(char32_t c);

/// CheckText, and more for a name people tell apart by how it reads (a sort plan's name, a bin):
/// no space or invisible character (IsBlank's) at either end, nor one inside but the plain space
/// and the zero-width joiners Indic words need (U+200C, U+200D, which may also end a word, as in
/// Malayalam's older chillu forms). " delhi", "delhi" and
/// "del<U+200B>hi" print alike, so three plans of those names all read "delhi" in a list.
std::optional<Error> CheckShownName(std::string_view field, std::string_view value,
                                    std::size_t max_bytes);

/// `text` in Unicode's Normalization Form C (canonical composition): "e" + U+0301 and "é" (U+00E9)
/// give the same bytes, as do a Devanagari consonant with U+093C nukta and its precomposed form.
/// What two names that read alike are compared by (two bins or plan names that differ in bytes
/// but not here would show as one and be two); text is stored as it was written. Text that is not
/// valid UTF-8, or holds a NUL, comes back unchanged. Canonical equivalence only: letters of other
/// scripts that look alike (Latin "a" and Cyrillic "а") stay apart.
std::string CanonicalForm(std::string_view text);

}  // namespace pintag::db
