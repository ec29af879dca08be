#include "request_head_check.hpp"

#include <cstdio>

#include "pintag/server/header_text.hpp"

namespace pintag::server {
namespace {

/// Long enough to recognise a header in a message, short enough to keep the message short.
constexpr std::size_t kNameKept = 64;

/// RFC 9110's tchar: what a header's name may hold.
bool IsTokenChar(char c) {
  if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) return true;
  switch (c) {
    case '!':
    case '#':
    case '$':
    case '%':
    case '&':
    case '\'':
    case '*':
    case '+':
    case '-':
    case '.':
    case '^':
    case '_':
    case '`':
    case '|':
    case '~':
      return true;
    default:
      return false;
  }
}

std::string Hex(char c) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
  return text;
}

/// Which of the headers held to their grammar `name` is, told without case.
RequestHeadCheck::Value ValueKind(const std::string& name) {
  const std::string lower = Lower(name);
  if (lower == "content-length") return RequestHeadCheck::Value::kLength;
  if (lower == "transfer-encoding") return RequestHeadCheck::Value::kCoding;
  if (lower == "authorization") return RequestHeadCheck::Value::kAuthorization;
  return RequestHeadCheck::Value::kOther;
}

}  // namespace

bool RequestHeadCheck::take(std::string_view bytes) {
  if (refusal_) return false;
  for (const char c : bytes) {
    if (where_ == Where::kEnded) return true;
    if (!takeByte(c)) return false;
  }
  return true;
}

bool RequestHeadCheck::takeByte(char c) {
  if (c == '\0') return refuse(400, "the request head holds a NUL byte");
  ++line_bytes_;
  if (where_ != Where::kRequestLine && line_bytes_ > kMaxHeaderLineBytes) {
    return refuse(431, "the header line" + nameSoFar() + " ran past " +
                           std::to_string(kMaxHeaderLineBytes) +
                           " bytes; a header line may be at most that long, its CRLF counted");
  }
  if (after_cr_) {
    after_cr_ = false;
    if (c != '\n') return refuse(400, "a CR in the request head is not followed by LF");
    switch (where_) {
      case Where::kRequestLine:
        break;
      case Where::kLineStart:
        where_ = Where::kEnded;
        return true;
      case Where::kName:
        return refuse(400, "the header line" + nameSoFar() + " has no colon");
      case Where::kValue:
        if (value_ == Value::kLength && !length_digit_) {
          return refuse(400, "the header \"Content-Length\" has no value");
        }
        break;
      case Where::kEnded:
        break;
    }
    where_ = Where::kLineStart;
    line_bytes_ = 0;
    name_.clear();
    return true;
  }
  if (c == '\r') {
    after_cr_ = true;
    return true;
  }
  if (c == '\n') {
    return refuse(400, "a line of the request head ends in a bare LF; lines end in CRLF");
  }
  switch (where_) {
    case Where::kLineStart:
      if (c == ' ' || c == '\t') {
        return refuse(400,
                      "a header line starts with whitespace (a line folded onto the one before "
                      "it, obs-fold); send each header on one line");
      }
      if (c == ':') return refuse(400, "a header line has no name before its colon");
      where_ = Where::kName;
      [[fallthrough]];
    case Where::kName:
      if (c == ':') {
        where_ = Where::kValue;
        value_ = ValueKind(name_);
        length_digit_ = false;
      } else if (c == ' ' || c == '\t') {
        return refuse(400, "the header" + nameSoFar() + " has whitespace between its name and " +
                               "its colon");
      } else if (!IsTokenChar(c)) {
        const std::string where = name_.empty()
                                      ? "a header name starts with "
                                      : "the header name" + nameSoFar() + " is followed by ";
        return refuse(400, where + Hex(c) + ", which a header name may not hold");
      } else if (name_.size() <= kNameKept) {
        name_ += c;
      }
      return true;
    case Where::kValue:
      return takeValueByte(c);
    case Where::kRequestLine:
    case Where::kEnded:
      return true;
  }
  return true;
}

bool RequestHeadCheck::takeValueByte(char c) {
  const auto byte = static_cast<unsigned char>(c);
  if ((byte < 0x20 && c != '\t') || byte == 0x7F) {
    return refuse(400, "the header" + nameSoFar() + " holds the control byte " + Hex(c));
  }
  // cpp-httplib 0.11.4 percent-decodes header values, so "%32%33" would be read as a length of
  // 23 and "%63hunked" as chunked, where a proxy reads neither: the two headers that frame the
  // body may hold only what their grammar allows.
  switch (value_) {
    case Value::kLength:
      if (c >= '0' && c <= '9') {
        length_digit_ = true;
      } else if (c != ' ' && c != '\t') {
        return refuse(400, "the header \"Content-Length\" may hold only digits, not " + Hex(c));
      }
      break;
    case Value::kCoding:
      if (c == '%' || (!IsTokenChar(c) && c != ' ' && c != '\t' && c != ',' && c != ';' &&
                       c != '=' && c != '"')) {
        return refuse(400, "the header \"Transfer-Encoding\" may not hold " + Hex(c));
      }
      break;
    case Value::kAuthorization:
      // A bearer token (RFC 6750's b64token) and Basic's base64 hold no `%`.
      if (c == '%') {
        return refuse(400,
                      "the header \"Authorization\" may not hold 0x25 ('%'): send the token as "
                      "it was given, 'Bearer <token>', not percent-encoded");
      }
      break;
    case Value::kOther:
      break;
  }
  return true;
}

bool RequestHeadCheck::refuse(int status, std::string detail) {
  refusal_ = Refusal{status, std::move(detail)};
  return false;
}

std::string RequestHeadCheck::nameSoFar() const {
  if (name_.empty()) return "";
  if (name_.size() > kNameKept) return " \"" + name_.substr(0, kNameKept) + "…\"";
  return " \"" + name_ + "\"";
}

}  // namespace pintag::server
