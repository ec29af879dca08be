#pragma once
// A colour rule decided by one table lookup. When a rule, once it holds for some R, holds for every
// larger R (G and B held), it is given by the least such R for each (G, B): 64 K entries instead of
// 16 M. LabApprox's a*, b* and L* all grow with R, so stage 1's redness is such a rule, and so is
// the negation of stage 2's ring test (not ring: a* >= 10 or L* >= 85); each table is tested
// against its rule over the whole sRGB cube, which is what shows that LabApprox keeps this.

#include <cstdint>
#include <functional>
#include <vector>

namespace pintag::stage {

/// For every (G, B), at index (G << 8) | B, the least R in 0 … 255 at which `holds(r, g, b)`, or
/// 256 when there is none. `holds` must be upward-closed in R; the table is found by bisection
/// (at most 9 evaluations for each (G, B)).
std::vector<std::uint16_t> LeastRTable(const std::function<bool(int r, int g, int b)>& holds);

}  // namespace pintag::stage
