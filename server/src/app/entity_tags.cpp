#include "app/entity_tags.hpp"

#include <algorithm>

#include "pintag/server/problem.hpp"

namespace pintag::app {
namespace {

bool IsSpace(char c) {
  return c == ' ' || c == '\t';
}

// etagc: "!" / %x23-7E / obs-text; no quote, no space, no control character.
bool IsTagChar(char c) {
  const auto byte = static_cast<unsigned char>(c);
  return byte == 0x21 || (byte >= 0x23 && byte != 0x7f);
}

/// Appends the tags of one header line to `list`; false when the line is malformed.
bool ParseLine(std::string_view text, EntityTagList& list) {
  std::size_t i = 0;
  bool any_element = false;
  while (i < text.size()) {
    while (i < text.size() && (IsSpace(text[i]) || text[i] == ',')) ++i;  // empty list elements
    if (i == text.size()) break;
    any_element = true;
    if (text[i] == '*') {
      list.any = true;
      ++i;
    } else {
      EntityTag tag;
      if (text.substr(i, 2) == "W/") {
        tag.weak = true;
        i += 2;
      }
      if (i == text.size() || text[i] != '"') return false;
      const std::size_t start = ++i;
      while (i < text.size() && IsTagChar(text[i])) ++i;
      if (i == text.size() || text[i] != '"') return false;
      tag.opaque = std::string(text.substr(start, i - start));
      ++i;
      list.tags.push_back(std::move(tag));
    }
    while (i < text.size() && IsSpace(text[i])) ++i;
    if (i < text.size() && text[i] != ',') return false;
  }
  return any_element;
}

}  // namespace

std::optional<EntityTagList> EntityTagsHeader(const server::HttpRequest& request,
                                              std::string_view name) {
  const auto [first, last] = request.headers.equal_range(name);
  if (first == last) return std::nullopt;
  EntityTagList list;
  for (auto line = first; line != last; ++line) {
    if (!ParseLine(line->second, list)) {
      throw server::HttpError(400, std::string(name) +
                                       " must be * or a list of quoted entity tags, such as "
                                       "\"1f0c…\" as an ETag gave it");
    }
  }
  // `*` stands alone (RFC 9110): mixed with tags it is a client's mistake, not a wider match.
  if (list.any && !list.tags.empty()) {
    throw server::HttpError(400, std::string(name) + ": * cannot be listed with entity tags");
  }
  return list;
}

bool NoneMatchNames(const EntityTagList& none_match, std::string_view etag) {
  if (none_match.any) return true;
  return std::any_of(none_match.tags.begin(), none_match.tags.end(), [&](const EntityTag& tag) {
    return etag.size() == tag.opaque.size() + 2 && etag.substr(1, tag.opaque.size()) == tag.opaque;
  });
}

}  // namespace pintag::app
