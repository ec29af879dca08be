#include "pintag/server/router.hpp"

#include <algorithm>
#include <stdexcept>

namespace pintag::server {
namespace {

std::vector<std::string_view> Split(std::string_view path) {
  std::vector<std::string_view> parts;
  if (path.empty() || path.front() != '/') return parts;
  std::size_t start = 1;
  while (true) {
    const std::size_t slash = path.find('/', start);
    parts.push_back(path.substr(start, slash - start));
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  return parts;
}

}  // namespace

Route MakeRoute(std::string method, std::string pattern, Access access, Handler handler,
                std::string summary, std::string tag) {
  Route route;
  route.method = std::move(method);
  route.pattern = std::move(pattern);
  route.access = access;
  route.handler = std::move(handler);
  route.summary = std::move(summary);
  route.tag = std::move(tag);
  return route;
}

Router::Compiled Router::Compile(const std::string& pattern) {
  if (pattern.empty() || pattern.front() != '/') {
    throw std::invalid_argument("route pattern must start with '/': " + pattern);
  }
  Compiled compiled;
  for (std::string_view part : Split(pattern)) {
    Segment segment;
    if (!part.empty() && part.front() == '{') {
      const std::size_t close = part.find('}');
      if (close == std::string_view::npos || close == 1) {
        throw std::invalid_argument("bad parameter in route pattern: " + pattern);
      }
      segment.param = true;
      segment.text = std::string(part.substr(1, close - 1));
      segment.suffix = std::string(part.substr(close + 1));
      if (segment.suffix.find_first_of("{}") != std::string::npos) {
        throw std::invalid_argument("one parameter per segment: " + pattern);
      }
    } else {
      if (part.find_first_of("{}") != std::string_view::npos) {
        throw std::invalid_argument("parameters must start a segment: " + pattern);
      }
      segment.text = std::string(part);
    }
    compiled.segments.push_back(std::move(segment));
  }
  return compiled;
}

bool Router::Matches(const Compiled& compiled, const std::vector<std::string_view>& parts,
                     std::map<std::string, std::string>* params) {
  if (parts.size() != compiled.segments.size()) return false;
  std::map<std::string, std::string> found;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const Segment& segment = compiled.segments[i];
    const std::string_view part = parts[i];
    if (!segment.param) {
      if (part != segment.text) return false;
      continue;
    }
    if (part.size() <= segment.suffix.size() || !part.ends_with(segment.suffix)) return false;
    found[segment.text] = std::string(part.substr(0, part.size() - segment.suffix.size()));
  }
  if (params != nullptr) *params = std::move(found);
  return true;
}

Router& Router::add(Route route) {
  Compiled compiled = Compile(route.pattern);
  for (const Route& existing : routes_) {
    if (existing.method == route.method && existing.pattern == route.pattern) {
      throw std::invalid_argument("duplicate route " + route.method + " " + route.pattern);
    }
  }
  if (!route.handler) throw std::invalid_argument("route without handler: " + route.pattern);
  routes_.push_back(std::move(route));
  compiled_.push_back(std::move(compiled));
  return *this;
}

RouteMatch Router::match(std::string_view method, std::string_view path) const {
  const std::string_view wanted = method == "HEAD" ? std::string_view("GET") : method;
  const std::vector<std::string_view> parts = Split(path);
  RouteMatch result;
  // Literal routes win over parameter routes where both match ("/pincodes/search" vs "{pin}"):
  // the first pass takes routes without parameters.
  for (int pass = 0; pass < 2 && result.route == nullptr; ++pass) {
    for (std::size_t i = 0; i < routes_.size(); ++i) {
      bool has_param = false;
      for (const Segment& s : compiled_[i].segments) has_param = has_param || s.param;
      if (has_param != (pass == 1)) continue;
      std::map<std::string, std::string> params;
      if (!Matches(compiled_[i], parts, &params)) continue;
      if (routes_[i].method == wanted) {
        result.route = &routes_[i];
        result.params = std::move(params);
        result.allowed_methods.clear();
        break;
      }
      std::vector<std::string>& allowed = result.allowed_methods;
      if (std::find(allowed.begin(), allowed.end(), routes_[i].method) == allowed.end()) {
        allowed.push_back(routes_[i].method);  // once, though two patterns may take it
      }
      if (result.allowed_pattern.empty()) result.allowed_pattern = routes_[i].pattern;
    }
  }
  if (result.route != nullptr) {
    result.allowed_methods.clear();
    result.allowed_pattern.clear();
  }
  return result;
}

}  // namespace pintag::server
