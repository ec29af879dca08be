#pragma once
// A token's secret is shown once: on standard output, or in a file only its owner can read. When
// it could not be written (stdout full or closed, the file's directory unwritable), the token is
// revoked rather than left working with a secret nobody knowingly holds.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "pintag/db/sqlite.hpp"

namespace pintag::cli {

/// When standard output failed (after a flush), revokes token `id` and throws std::runtime_error
/// saying so (and, should revoking fail, the command that revokes it).
void RevokeIfStdoutFailed(db::Connection& connection, std::int64_t id);

/// Writes `secret` and a newline to `path`, readable and writable by its owner only (0600),
/// atomically: a temporary file beside it, synced, then renamed over it, so a reader (a replica
/// re-reading its token file on SIGHUP) never sees half of one; through a symbolic link, the file
/// it names (FileReplacedBy: a device or a pipe is refused). Empty on success, else why not.
std::string WriteSecretFile(const std::filesystem::path& path, std::string_view secret);

/// When `failure` is not empty, revokes token `id` and throws std::runtime_error saying the
/// secret could not be written to `where` and why.
void RevokeIfUnwritten(db::Connection& connection, std::int64_t id, std::string_view where,
                       std::string_view failure);

}  // namespace pintag::cli
