#pragma once
// SHA-256 through OpenSSL, for the token hashes and the sort plans' versions.

#include <initializer_list>
#include <string>
#include <string_view>

namespace pintag::db::detail {

/// The 32-byte digest of `parts` one after the other; throws std::runtime_error when OpenSSL
/// fails.
std::string Sha256(std::initializer_list<std::string_view> parts);

}  // namespace pintag::db::detail
