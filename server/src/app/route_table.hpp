#pragma once
// The application's route table: every /api/v1 route with its method, path, role and handler,
// and what OpenAPI says about it. /openapi.json is generated from it (server::OpenApiJson).

#include <memory>

#include "app/context.hpp"
#include "pintag/server/router.hpp"

namespace pintag::app {

/// A router holding every application route, its handlers bound to `context`.
server::Router AppRouter(const std::shared_ptr<const AppContext>& context);

}  // namespace pintag::app
