#pragma once
// An OpenAPI 3.1 description generated from the route table, so it cannot drift from it.

#include <string>

#include "pintag/server/router.hpp"

namespace pintag::server {

struct ApiInfo {
  std::string title = "PinTag";
  std::string version = "0.1.0";
  std::string description = "PinTag labels, detection, registry and routing";
};

/// The OpenAPI 3.1 document (JSON text) of every route that is not hidden: path parameters,
/// documented query parameters, request media types, success media types, the problem+json error
/// responses, bearer security where the route needs a role, and that role (open, counter,
/// scanner, admin) as the extension field "x-pintag-role" of every operation.
std::string OpenApiJson(const Router& router, const ApiInfo& info = {});

}  // namespace pintag::server
