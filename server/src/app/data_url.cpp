#include "app/data_url.hpp"

#include <cstdint>

namespace pintag::app {

std::string DataUrl(std::string_view media_type, std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string url = "data:" + std::string(media_type) + ";base64,";
  url.reserve(url.size() + (bytes.size() + 2) / 3 * 4);
  const auto byte = [&](std::size_t i) -> std::uint32_t {
    return i < bytes.size() ? static_cast<unsigned char>(bytes[i]) : 0U;
  };
  // Each 3 bytes become 4 characters of 6 bits; a short last group is padded with '='.
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t group = (byte(i) << 16) | (byte(i + 1) << 8) | byte(i + 2);
    const std::size_t left = bytes.size() - i;
    url += kAlphabet[(group >> 18) & 0x3F];
    url += kAlphabet[(group >> 12) & 0x3F];
    url += left > 1 ? kAlphabet[(group >> 6) & 0x3F] : '=';
    url += left > 2 ? kAlphabet[group & 0x3F] : '=';
  }
  return url;
}

}  // namespace pintag::app
