#pragma once
// Whether the server could listen on an address and port, and if not why, in the system's words:
// asked before a start does slow work (creating and seeding a database) and when binding fails,
// since cpp-httplib's bind reports only that it failed.

#include <string>

namespace pintag::server {

/// Empty when a TCP socket can be bound to `address`:`port` now (it is closed again at once),
/// else why not: the address does not resolve, "Address already in use", "Cannot assign
/// requested address" (not an address of this host), "Permission denied" (a port under 1024).
std::string WhyCannotListen(const std::string& address, int port);

}  // namespace pintag::server
