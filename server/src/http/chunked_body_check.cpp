#include "chunked_body_check.hpp"

#include <algorithm>
#include <utility>

namespace pintag::server {
namespace {

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

bool ChunkedBodyCheck::refuse(std::string detail) {
  refusal_ = "the chunked body is malformed: " + std::move(detail);
  return false;
}

bool ChunkedBodyCheck::take(std::string_view bytes) {
  if (refusal_) return false;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const char c = bytes[i];
    switch (where_) {
      case Where::kSizeStart:
        if (HexValue(c) < 0) return refuse("a chunk size must start with a hexadecimal digit");
        size_ = static_cast<std::uint64_t>(HexValue(c));
        digits_ = size_ == 0 ? 0 : 1;
        where_ = Where::kSize;
        break;
      case Where::kSize:
        if (HexValue(c) >= 0) {
          // Leading zeros are allowed and not counted: the line's length is bounded elsewhere.
          if ((size_ != 0 || HexValue(c) != 0) && ++digits_ > kMaxSizeDigits) {
            return refuse("a chunk size may have at most " + std::to_string(kMaxSizeDigits) +
                          " hexadecimal digits after its leading zeros");
          }
          size_ = size_ * 16 + static_cast<std::uint64_t>(HexValue(c));
        } else if (c == ';' || c == ' ' || c == '\t') {
          where_ = Where::kExtension;
        } else if (c == '\r') {
          where_ = Where::kSizeLf;
        } else if (c == '\n') {
          return refuse("a chunk size line must end in CRLF, not a bare LF");
        } else {
          return refuse("a chunk size is hexadecimal digits only (no 0x, sign or other character)");
        }
        break;
      case Where::kExtension:
        if (c == '\r') {
          where_ = Where::kSizeLf;
        } else if ((static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f) {
          return refuse(c == '\n' ? "a chunk size line must end in CRLF, not a bare LF"
                                  : "a chunk extension holds a control character");
        }
        break;
      case Where::kSizeLf:
        if (c != '\n') return refuse("a chunk size line must end in CRLF");
        data_left_ = size_;
        where_ = size_ == 0 ? Where::kEndCr : Where::kData;
        break;
      case Where::kData: {
        // The data itself is not looked at: skip over as much of it as this read holds.
        const auto skip = static_cast<std::size_t>(
            std::min<std::uint64_t>(data_left_, static_cast<std::uint64_t>(bytes.size() - i)));
        data_left_ -= skip;
        i += skip - 1;
        if (data_left_ == 0) where_ = Where::kDataCr;
        break;
      }
      case Where::kDataCr:
        if (c != '\r') {
          return refuse(
              "a chunk's data must be followed by CRLF: it is longer than its size says, "
              "or its line ends otherwise");
        }
        where_ = Where::kDataLf;
        break;
      case Where::kDataLf:
        if (c != '\n') return refuse("a chunk's data must be followed by CRLF");
        where_ = Where::kSizeStart;
        break;
      case Where::kEndCr:
        if (c != '\r') {
          return refuse(
              "the last chunk must be followed by an empty line (trailer fields are not "
              "read)");
        }
        where_ = Where::kEndLf;
        break;
      case Where::kEndLf:
        if (c != '\n') return refuse("the empty line after the last chunk must end in CRLF");
        where_ = Where::kEnded;
        break;
      case Where::kEnded:
        return refuse("bytes were read after its end");
    }
  }
  return true;
}

}  // namespace pintag::server
