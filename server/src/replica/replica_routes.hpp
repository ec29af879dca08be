#pragma once
// The routes of a scaled-out registry: the primary hands its snapshot to replicas, every server
// says which registry version it serves, and a read-only replica refuses writes, naming the
// primary to send them to.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "pintag/db/result.hpp"
#include "pintag/server/router.hpp"
#include "replica/snapshot_publisher.hpp"

namespace pintag::replica {

/// GET /api/v1/registry/snapshot (replica or admin token): the published snapshot as
/// application/vnd.sqlite3 with ETag "<version>"; 304 when If-None-Match names the live version.
void AddSnapshotRoute(server::Router& router, const std::shared_ptr<SnapshotPublisher>& publisher);

/// What GET /api/v1/registry (open) reports.
struct RegistryStatus {
  std::function<db::Result<std::int64_t>()> version;  ///< the registry version served now
  std::string role;                                   ///< "primary" or "replica"
  std::optional<std::string> primary_url;             ///< a replica's primary, when known
};
void AddRegistryStatusRoute(server::Router& router, RegistryStatus status);

/// Whether a route changes the registry: every admin route but a GET (pincodes, sort plans,
/// tokens). Detection and batch labels are POSTs that change nothing and stay open to replicas.
bool ChangesRegistry(const server::Route& route);

/// `router` for a read-only replica: each route that ChangesRegistry answers 403 "Read-Only
/// Replica" naming `primary_url`, before asking for a token (the body is not parsed).
server::Router ReadOnlyRouter(const server::Router& router, const std::string& primary_url);

}  // namespace pintag::replica
