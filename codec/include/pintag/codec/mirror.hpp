#pragma once
// A format-v1 tag seen in a mirror. The format has no mark of handedness: a tag flipped left to
// right (a front camera's "mirror photos" setting, a label read from the back through film) is
// drawn exactly like another valid tag for about one key in 32, the ones whose mirrored payload
// happens to pass the parity. No reader can tell the two apart from the tag alone, so the system
// says so where such a pair is in the registry (docs/FORMAT.md, "Mirror images").

#include <optional>

#include "pintag/codec/cells.hpp"
#include "pintag/codec/tag_key.hpp"

namespace pintag {

/// The cells of `cells`' tag flipped left to right: C0 and C1 trade places, as do C3 and C2, and
/// every angle θ becomes −θ (sector s becomes 7 − s, quadrant q becomes 3 − q). Flipped top to
/// bottom it is the same tag turned half a turn, so that mirror reads alike.
TagCells MirrorCells(const TagCells& cells);

/// The key whose tag is `key`'s tag mirrored, or nothing when the mirror image is no valid tag
/// (it then reads as nothing). Mirroring twice gives the key back.
std::optional<TagKey> MirrorImageKey(TagKey key);

}  // namespace pintag
