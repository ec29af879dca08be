#include "pintag/server/openapi.hpp"

#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>

#include "pintag/server/problem.hpp"

namespace pintag::server {
namespace {

using nlohmann::json;

std::vector<std::string> PathParams(const std::string& pattern) {
  std::vector<std::string> names;
  for (std::size_t open = pattern.find('{'); open != std::string::npos;
       open = pattern.find('{', open + 1)) {
    const std::size_t close = pattern.find('}', open);
    if (close == std::string::npos) break;
    names.push_back(pattern.substr(open + 1, close - open - 1));
  }
  return names;
}

json ProblemRef(std::string description) {
  return {{"description", std::move(description)},
          {"content",
           {{std::string(kProblemContentType),
             {{"schema", {{"$ref", "#/components/schemas/Problem"}}}}}}}};
}

std::string OperationId(const Route& route) {
  std::string id;
  for (char c : route.method) id += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  bool upper = true;
  for (char c : route.pattern) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      id += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
      upper = false;
    } else {
      upper = true;
    }
  }
  return id;
}

/// A success's reason phrase, as its response's description (StatusTitle names errors).
std::string SuccessDescription(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 201:
      return "Created";
    case 304:
      return "Not Modified: If-None-Match named the current version (no body)";
    default:
      return "Success";
  }
}

bool IsBinary(const std::string& media_type) {
  return media_type.rfind("image/", 0) == 0 || media_type == "application/pdf" ||
         media_type == "application/octet-stream";
}

}  // namespace

std::string OpenApiJson(const Router& router, const ApiInfo& info) {
  json paths = json::object();
  bool any_secured = false;
  for (const Route& route : router.routes()) {
    if (route.hidden) continue;
    json op;
    op["operationId"] = OperationId(route);
    op["summary"] = route.summary;
    op["tags"] = json::array({route.tag});
    // The role in one word, so a reader (and the docs test) need not parse "security".
    op["x-pintag-role"] = std::string(ToString(route.access));
    json parameters = json::array();
    for (const std::string& name : PathParams(route.pattern)) {
      parameters.push_back(
          {{"name", name}, {"in", "path"}, {"required", true}, {"schema", {{"type", "string"}}}});
    }
    for (const QueryParamDoc& q : route.query) {
      parameters.push_back({{"name", q.name},
                            {"in", "query"},
                            {"required", q.required},
                            {"description", q.description},
                            {"schema", {{"type", q.type}}}});
    }
    for (const HeaderDoc& header : route.request_headers) {
      parameters.push_back({{"name", header.name},
                            {"in", "header"},
                            {"required", false},
                            {"description", header.description},
                            {"schema", {{"type", "string"}}}});
    }
    if (!parameters.empty()) op["parameters"] = parameters;
    if (!route.consumes.empty()) {
      json content = json::object();
      for (const std::string& type : route.consumes) {
        content[type] = IsBinary(type)
                            ? json{{"schema", {{"type", "string"}, {"contentMediaType", type}}}}
                            : json{{"schema", json::object()}};
      }
      op["requestBody"] = {{"required", true}, {"content", content}};
    }
    json content = json::object();
    const std::vector<std::string> produces =
        route.produces.empty() ? std::vector<std::string>{"application/json"} : route.produces;
    for (const std::string& type : produces) {
      content[type] = IsBinary(type)
                          ? json{{"schema", {{"type", "string"}, {"contentMediaType", type}}}}
                          : json{{"schema", json::object()}};
    }
    json responses = json::object();
    json headers = json::object();
    for (const HeaderDoc& header : route.response_headers) {
      headers[header.name] = {{"description", header.description},
                              {"schema", {{"type", "string"}}}};
    }
    for (const int status : route.success) {
      json& response = responses[std::to_string(status)];
      response = {{"description", SuccessDescription(status)}};
      if (status != 304) response["content"] = content;
      if (!headers.empty()) response["headers"] = headers;
    }
    responses["4XX"] = ProblemRef("client error (problem details, RFC 9457)");
    responses["5XX"] = ProblemRef("server error (problem details, RFC 9457)");
    if (route.access != Access::kOpen) {
      any_secured = true;
      op["security"] = json::array({{{"bearer", json::array()}}});
      op["description"] = "Needs a bearer token with role " + std::string(ToString(route.access)) +
                          (route.access == Access::kAdmin ? "." : " or admin.");
      responses["401"] = ProblemRef("missing or invalid bearer token");
      responses["403"] = ProblemRef("the token's role may not call this route");
    }
    op["responses"] = responses;
    std::string method = route.method;
    std::transform(method.begin(), method.end(), method.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    paths[route.pattern][method] = op;
  }

  json doc = {
      {"openapi", "3.1.0"},
      {"info",
       {{"title", info.title}, {"version", info.version}, {"description", info.description}}},
      {"paths", paths},
      {"components",
       {{"schemas",
         {{"Problem",
           {{"type", "object"},
            {"required", json::array({"type", "title", "status", "detail"})},
            {"properties",
             {{"type", {{"type", "string"}, {"format", "uri-reference"}}},
              {"title", {{"type", "string"}}},
              {"status", {{"type", "integer"}}},
              {"detail", {{"type", "string"}}},
              {"max_pixels",
               {{"type", "integer"},
                {"description", "413 Image Too Large: the server's pixel limit per photo"}}},
              {"width",
               {{"type", "integer"},
                {"description", "413 Image Too Large: the photo's width as stored"}}},
              {"height",
               {{"type", "integer"},
                {"description", "413 Image Too Large: the photo's height as stored"}}},
              {"max_body_bytes",
               {{"type", "integer"},
                {"description", "413 for a body over the limit: the limit in bytes"}}},
              {"max_batch",
               {{"type", "integer"},
                {"description",
                 "413 for a batch of labels over the limit: labels per request"}}}}}}}}}}},
  };
  if (any_secured) {
    doc["components"]["securitySchemes"] = {{"bearer", {{"type", "http"}, {"scheme", "bearer"}}}};
  }
  return doc.dump(2);
}

}  // namespace pintag::server
