#pragma once
// A read-only replica's routes: the route table with every write refused, naming the primary to
// send it to. (The replication routes themselves are rows of app/route_table.cpp.)

#include <string>

#include "pintag/server/router.hpp"

namespace pintag::replica {

/// Whether a route changes the registry: every admin route but a GET (pincodes, sort plans,
/// tokens). Detection and batch labels are POSTs that change nothing and stay open to replicas.
bool ChangesRegistry(const server::Route& route);

/// `router` for a read-only replica: each route that ChangesRegistry answers 403 "Read-Only
/// Replica" naming `primary_url` (empty: not told which), before asking for a token (the body is
/// not parsed).
server::Router ReadOnlyRouter(const server::Router& router, const std::string& primary_url);

}  // namespace pintag::replica
