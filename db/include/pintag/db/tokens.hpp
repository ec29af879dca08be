#pragma once
// API tokens. A token's secret is shown once, at creation; the database keeps only a random
// 16-byte salt and SHA-256(salt ‖ secret). Secrets are `pt_<id>_<43 base64url characters>`
// (256 random bits from getrandom), so verifying looks up one row by id and compares hashes in
// constant time.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pintag/db/result.hpp"
#include "pintag/db/sqlite.hpp"

namespace pintag::db {

/// kReplica: a read-only replica pulling registry snapshots from the primary, and nothing else.
enum class Role { kAdmin, kCounter, kScanner, kReplica };
const char* ToString(Role role);                       ///< "admin", "counter", "scanner", "replica"
std::optional<Role> ParseRole(std::string_view text);  ///< exact lower-case names

struct TokenInfo {
  std::int64_t id = 0;
  Role role = Role::kScanner;
  std::string label;                      ///< free text given at creation, may be empty
  std::string created_at;                 ///< ISO 8601 UTC
  std::optional<std::string> revoked_at;  ///< set once revoked
};

struct NewToken {
  TokenInfo info;
  std::string secret;  ///< the only copy: give it to the user now
};

/// Nothing when `label` may label a token: empty, or text CheckText takes (at most
/// kMaxLabelBytes) that is not blank; a label of only spaces names nothing in a list.
std::optional<Error> CheckTokenLabel(std::string_view label);

Result<NewToken> CreateToken(Connection& connection, Role role, std::string_view label = "");
Result<std::vector<TokenInfo>> ListTokens(Connection& connection);  ///< by id, revoked included
/// One token (never its secret); kNotFound when there is none with that id.
Result<TokenInfo> GetToken(Connection& connection, std::int64_t id);
/// Whether RevokeToken may revoke the last active admin token.
enum class LastAdmin {
  kMayRevoke,  ///< the command line: whoever runs it can make another
  kKeep,       ///< the API: revoked, nobody could administer the server through it again
};
/// kNotFound for an unknown id; revoking a revoked token is a no-op. With LastAdmin::kKeep, the
/// last active admin token is kConflict (checked and revoked in one transaction, so two admins
/// revoking each other at once cannot both go).
Result<TokenInfo> RevokeToken(Connection& connection, std::int64_t id,
                              LastAdmin last_admin = LastAdmin::kMayRevoke);
/// The token the secret belongs to; kUnauthorized (one message for every cause) when it is
/// malformed, unknown, wrong or revoked.
Result<TokenInfo> VerifyToken(Connection& connection, std::string_view secret);
/// Whether `secret` has the form CreateToken gives one: pt_, the token's id, _, and 43 base64url
/// characters (32 random bytes). For a secret handed to a command (a follower's), so that a typo
/// is said at once rather than as the primary's 401 at every poll.
bool HasTokenForm(std::string_view secret);

}  // namespace pintag::db
