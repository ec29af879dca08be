#pragma once
// A replica token kept in a file (--follow-token-file): its first line, without the line end or
// trailing spaces, as `pintag token create --out` writes it.

#include <optional>
#include <string>

namespace pintag::replica {

/// The token in the file at `path`; nothing when it cannot be read or holds none.
std::optional<std::string> ReadTokenFile(const std::string& path);

}  // namespace pintag::replica
