#pragma once
// Entity tags in conditional requests (RFC 9110 §8.8.3, §13.1.1–13.1.2): the If-Match and
// If-None-Match headers a client sends to make a write depend on the version it read.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pintag/server/http_types.hpp"

namespace pintag::app {

struct EntityTag {
  std::string opaque;  ///< between the quotes
  bool weak = false;   ///< written W/"…"
};

/// An If-Match or If-None-Match value: `*`, or a list of entity tags.
struct EntityTagList {
  bool any = false;  ///< `*`
  std::vector<EntityTag> tags;
};

/// Every line of header `name` read as one list (RFC 9110 §5.3); nothing when it is absent.
/// 400 naming the header when it is neither `*` nor a comma-separated list of quoted tags.
std::optional<EntityTagList> EntityTagsHeader(const server::HttpRequest& request,
                                              std::string_view name);

/// If-None-Match's weak comparison (RFC 9110 §13.1.2): `*`, or a tag whose opaque part is that
/// of `etag` (as an ETag header writes it, quoted), weak or not. A GET it names is answered 304.
bool NoneMatchNames(const EntityTagList& none_match, std::string_view etag);

}  // namespace pintag::app
