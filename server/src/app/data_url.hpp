#pragma once
// RFC 2397 data URLs: bytes carried inside JSON, e.g. the outlined photo of POST /api/v1/detect
// ?overlay=inline, which a page can show as an <img> without a second request.

#include <string>
#include <string_view>

namespace pintag::app {

/// "data:<media_type>;base64,<bytes in base64>" (RFC 4648 alphabet, padded).
std::string DataUrl(std::string_view media_type, std::string_view bytes);

}  // namespace pintag::app
