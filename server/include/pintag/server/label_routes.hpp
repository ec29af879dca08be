#pragma once
// Tag and label routes (issue 5), independent of where label content comes from: the registry
// plugs in as a LabelContentProvider.
//
//   GET  /api/v1/tags/{pin}.png     ?px=256&dpi=300   tag only, raster, dpi recorded
//   GET  /api/v1/tags/{pin}.svg     ?mm=50 | ?px=     tag only, vector
//   GET  /api/v1/labels/{pin}.pdf   ?size=100x150mm|a6|4x6in&plan=
//   GET  /api/v1/labels/{pin}.png   ?size=&dpi=300&plan=
//   GET  /api/v1/labels/{pin}.svg   ?size=&plan=
//   POST /api/v1/labels             {"pincodes": [...], "size": "a6", "plan": "..."} -> one PDF
//
// All need a counter (or admin) token. Each rendered tag or label counts in the metrics counters
// kTagsRenderedCounter and kLabelsRenderedCounter.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "pintag/codec/label.hpp"
#include "pintag/codec/pincode.hpp"
#include "pintag/server/metrics.hpp"
#include "pintag/server/problem.hpp"
#include "pintag/server/router.hpp"

namespace pintag::server {

inline constexpr std::string_view kLabelsRenderedCounter = "pintag_labels_rendered_total";
inline constexpr std::string_view kTagsRenderedCounter = "pintag_tags_rendered_total";

/// What the registry says about a pincode for a label: the content, or the problem to answer
/// (404 unknown pincode, 410 retired, 404 unknown plan, …).
struct LabelLookup {
  std::optional<LabelContent> label;
  std::optional<Problem> problem;
};

/// Resolves a pincode (and the sort plan, if one was asked for) to label content: key, main
/// office, district, state, bin. Must be thread-safe.
using LabelContentProvider =
    std::function<LabelLookup(Pincode pincode, const std::optional<std::string>& plan)>;

struct LabelRouteOptions {
  std::size_t max_batch = 100;  ///< labels per POST /api/v1/labels; more answers 413
  int max_tag_px = 4096;        ///< largest ?px= for tag PNGs (square side)
};

/// Adds the routes above to `router`.
void AddLabelRoutes(Router& router, LabelContentProvider provider, std::shared_ptr<Metrics> metrics,
                    LabelRouteOptions options = {});

}  // namespace pintag::server
