#pragma once
// The syntax of a request's head, checked byte by byte as the head is read (ConnectionStream
// feeds it). cpp-httplib 0.11.4 is lenient where leniency lets a proxy and this server read one
// stream as different requests: it skips a header line that ends in a bare LF or has no colon,
// and keeps `Content-Length : 5` as a header named "Content-Length " that it then ignores. A
// proxy that reads such a line otherwise finds a body where this server finds the next request.
// RFC 9112 asks a server to refuse these heads (400), so they are refused, each with its reason:
//   - a line that ends in a bare LF, or holds a CR that is not followed by LF;
//   - a header line that starts with a space or tab (obs-fold, a line folded onto the last);
//   - whitespace between a header's name and its colon; a name that is empty or holds a
//     character a name may not hold; a header line without a colon;
//   - a NUL anywhere in the head, a control byte (other than tab) in a header's value;
//   - a Content-Length that is not digits (or is empty), a Transfer-Encoding holding `%` or what
//     its grammar does not allow: cpp-httplib percent-decodes header values;
//   - an Authorization holding `%`: decoded, "Bearer%20<token>" or a token spelt in escapes would
//     be let in, where a proxy or log filter that looks at the header sees something else.
// A header line longer than kMaxHeaderLineBytes is refused with 431 naming the limit (cpp-httplib
// would answer 400 without a reason). The request line is left to cpp-httplib (414 past 8 KiB).

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace pintag::server {

class RequestHeadCheck {
 public:
  /// cpp-httplib's own bound on a header line (CPPHTTPLIB_HEADER_MAX_LENGTH), its CRLF counted.
  static constexpr std::size_t kMaxHeaderLineBytes = std::size_t{8} * 1024;

  /// The headers whose values are held to their grammar: the two that frame a request's body,
  /// and the credentials.
  enum class Value { kOther, kLength, kCoding, kAuthorization };

  struct Refusal {
    int status = 400;
    std::string detail;
  };

  /// Takes the next bytes of the head. False once the head has broken a rule (`refusal` says
  /// which); bytes after the blank line that ends the head are not looked at.
  bool take(std::string_view bytes);

  /// The blank line that ends the head has been taken.
  bool ended() const { return where_ == Where::kEnded; }
  const std::optional<Refusal>& refusal() const { return refusal_; }

 private:
  enum class Where { kRequestLine, kLineStart, kName, kValue, kEnded };

  bool takeByte(char c);
  bool takeValueByte(char c);
  bool refuse(int status, std::string detail);
  std::string nameSoFar() const;

  Where where_ = Where::kRequestLine;
  bool after_cr_ = false;        ///< the last byte was a CR, so this one must be LF
  std::size_t line_bytes_ = 0;   ///< bytes of the current line, its terminator counted
  std::string name_;             ///< the current header's name, as far as it is kept
  Value value_ = Value::kOther;  ///< which header the current value belongs to
  bool length_digit_ = false;    ///< a digit of the current Content-Length has come
  std::optional<Refusal> refusal_;
};

}  // namespace pintag::server
