#include "commands/unseen_token.hpp"

#include <iostream>
#include <stdexcept>
#include <string>

#include "pintag/db/tokens.hpp"

namespace pintag::cli {

void RevokeIfStdoutFailed(db::Connection& connection, std::int64_t id) {
  if (std::cout) return;
  const std::string name = std::to_string(id);
  auto revoked = db::RevokeToken(connection, id);
  if (!revoked) {
    throw std::runtime_error("cannot write the secret of token " + name +
                             " to standard output, and revoking it failed (" +
                             revoked.error().message + "): run `pintag token revoke " + name + "`");
  }
  throw std::runtime_error("cannot write the secret of token " + name +
                           " to standard output; the token is revoked");
}

}  // namespace pintag::cli
