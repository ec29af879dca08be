#pragma once
// The framing of a chunked request body, checked byte by byte as the body is read
// (ConnectionStream feeds it). cpp-httplib 0.11.4 reads chunk sizes with strtoul, so `0x23`, `+23`
// and `23zz` pass as 0x23, and when a chunk's data is not followed by a bare CRLF it ends the body
// there and reads what follows as the next request. A proxy that passes such a body on as it came
// finds a body where this server finds a request (request smuggling). RFC 9112 (7.1) is held to,
// and anything else is refused (400, the connection closed), each with its reason:
//   - a chunk size that is not hexadecimal digits, at most 16 after any leading zeros;
//   - a chunk size line, a chunk's data or the last line not ended by CRLF (a bare LF included);
//   - chunk data longer than its size says;
//   - trailer fields after the last chunk (cpp-httplib does not read them either);
//   - a control byte other than tab in a chunk extension (extensions are otherwise ignored).
// The length of a chunk-size line is ConnectionStream's to bound (kMaxBodyLineBytes).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace pintag::server {

class ChunkedBodyCheck {
 public:
  /// More would not fit in 64 bits; a body is limited far below that anyway.
  static constexpr std::size_t kMaxSizeDigits = 16;

  /// Takes the body's next bytes. False once the framing is broken (`refusal` says how).
  bool take(std::string_view bytes);

  /// The empty line after the last chunk has been taken: the body is whole.
  bool ended() const { return where_ == Where::kEnded; }
  const std::optional<std::string>& refusal() const { return refusal_; }

 private:
  enum class Where {
    kSizeStart,  ///< a chunk's first size digit
    kSize,       ///< more size digits, an extension or CR
    kExtension,  ///< after the size: extensions until CR
    kSizeLf,     ///< the LF of the size line
    kData,       ///< `data_left_` bytes of data
    kDataCr,     ///< the CRLF after a chunk's data
    kDataLf,
    kEndCr,  ///< the empty line after the last chunk
    kEndLf,
    kEnded,
  };

  bool refuse(std::string detail);

  Where where_ = Where::kSizeStart;
  std::uint64_t size_ = 0;
  std::size_t digits_ = 0;  ///< the size's digits after its leading zeros
  std::uint64_t data_left_ = 0;
  std::optional<std::string> refusal_;
};

}  // namespace pintag::server
