#pragma once
// A token's secret is shown once, on standard output. When it could not be written (stdout full or
// closed), the token is revoked rather than left working with a secret nobody knowingly holds.

#include <cstdint>

#include "pintag/db/sqlite.hpp"

namespace pintag::cli {

/// When standard output failed (after a flush), revokes token `id` and throws std::runtime_error
/// saying so (and, should revoking fail, the command that revokes it).
void RevokeIfStdoutFailed(db::Connection& connection, std::int64_t id);

}  // namespace pintag::cli
