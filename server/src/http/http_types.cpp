#include "pintag/server/http_types.hpp"

#include <algorithm>
#include <cctype>

namespace pintag::server {

std::string_view ToString(Access access) {
  switch (access) {
    case Access::kOpen:
      return "open";
    case Access::kCounter:
      return "counter";
    case Access::kScanner:
      return "scanner";
    case Access::kAdmin:
      return "admin";
    case Access::kReplica:
      return "replica";
  }
  return "unknown";
}

bool Allows(Access required, Access granted) {
  return required == Access::kOpen || granted == Access::kAdmin || required == granted;
}

bool CaseInsensitiveLess::operator()(std::string_view a, std::string_view b) const {
  return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) <
           std::tolower(static_cast<unsigned char>(y));
  });
}

std::string HttpRequest::pathParam(std::string_view name) const {
  const auto it = path_params.find(std::string(name));
  return it == path_params.end() ? std::string() : it->second;
}

std::optional<std::string> HttpRequest::queryParam(std::string_view name) const {
  const auto it = query.find(std::string(name));
  if (it == query.end()) return std::nullopt;
  return it->second;
}

const FormPart* HttpRequest::part(std::string_view name) const {
  for (const FormPart& p : parts) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

std::optional<std::string> HttpRequest::header(std::string_view name) const {
  const auto it = headers.find(name);
  if (it == headers.end()) return std::nullopt;
  return it->second;
}

HttpResponse HttpResponse::Json(std::string body, int status) {
  return {status, "application/json", std::move(body), {}};
}

HttpResponse HttpResponse::Bytes(std::string content_type, std::string body, int status) {
  return {status, std::move(content_type), std::move(body), {}};
}

HttpResponse HttpResponse::Bytes(std::string content_type, const std::vector<std::uint8_t>& body) {
  return {200, std::move(content_type), std::string(body.begin(), body.end()), {}};
}

HttpResponse HttpResponse::Text(std::string body, int status) {
  return {status, "text/plain; charset=utf-8", std::move(body), {}};
}

}  // namespace pintag::server
