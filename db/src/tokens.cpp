#include "pintag/db/tokens.hpp"

#include <openssl/crypto.h>
#include <sys/random.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

#include "guard.hpp"
#include "pintag/db/text.hpp"
#include "sha256.hpp"

namespace pintag::db {
namespace {

using detail::Guard;

constexpr std::size_t kSaltBytes = 16;
constexpr std::size_t kSecretBytes = 32;

std::string RandomBytes(std::size_t count) {
  std::string bytes(count, '\0');
  std::size_t done = 0;
  while (done < count) {
    const ssize_t got = getrandom(bytes.data() + done, count - done, 0);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("getrandom: ") + std::strerror(errno));
    }
    done += static_cast<std::size_t>(got);
  }
  return bytes;
}

std::string Base64Url(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_";
  std::string out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (const char c : bytes) {
    buffer = (buffer << 8) | static_cast<unsigned char>(c);
    bits += 8;
    while (bits >= 6) {
      bits -= 6;
      out += kAlphabet[(buffer >> bits) & 63];
    }
  }
  if (bits > 0) out += kAlphabet[(buffer << (6 - bits)) & 63];
  return out;
}

std::string Sha256(std::string_view salt, std::string_view secret) {
  return detail::Sha256({salt, secret});
}

TokenInfo ReadInfo(const Statement& s) {
  return {s.getInt64(0), *ParseRole(s.getText(1)), s.getText(2), s.getText(3),
          s.getOptionalText(4)};
}

constexpr const char* kInfoColumns = "id, role, label, created_at, revoked_at";

Result<TokenInfo> LoadInfo(Connection& connection, std::int64_t id) {
  Statement s =
      connection.prepare(std::string("SELECT ") + kInfoColumns + " FROM api_tokens WHERE id = ?1");
  s.bind(1, id);
  if (!s.step()) return Error{ErrorCode::kNotFound, "no token " + std::to_string(id)};
  return ReadInfo(s);
}

}  // namespace

const char* ToString(Role role) {
  switch (role) {
    case Role::kAdmin:
      return "admin";
    case Role::kCounter:
      return "counter";
    case Role::kScanner:
      return "scanner";
    case Role::kReplica:
      return "replica";
  }
  return "scanner";
}

std::optional<Role> ParseRole(std::string_view text) {
  if (text == "admin") return Role::kAdmin;
  if (text == "counter") return Role::kCounter;
  if (text == "scanner") return Role::kScanner;
  if (text == "replica") return Role::kReplica;
  return std::nullopt;
}

std::optional<Error> CheckTokenLabel(std::string_view label) {
  if (auto error = CheckText("label", label, kMaxLabelBytes, true)) return error;
  if (!label.empty() && IsBlank(label)) {
    return Error{ErrorCode::kInvalid,
                 "label is blank (only spaces or invisible characters); leave it out instead"};
  }
  return std::nullopt;
}

Result<NewToken> CreateToken(Connection& connection, Role role, std::string_view label) {
  if (auto error = CheckTokenLabel(label)) return *error;
  return Guard([&]() -> Result<NewToken> {
    try {
      Transaction transaction(connection);
      // The id is part of the secret, so the row comes first and its hash second.
      connection
          .prepare(std::string("INSERT INTO api_tokens (role, label, salt, secret_hash, "
                               "created_at) VALUES (?1, ?2, x'', x'', ") +
                   detail::kNowSql + ")")
          .bind(1, ToString(role))
          .bind(2, label)
          .run();
      const std::int64_t id = connection.lastInsertRowid();
      const std::string salt = RandomBytes(kSaltBytes);
      const std::string secret =
          "pt_" + std::to_string(id) + "_" + Base64Url(RandomBytes(kSecretBytes));
      const std::string hash = Sha256(salt, secret);
      connection.prepare("UPDATE api_tokens SET salt = ?1, secret_hash = ?2 WHERE id = ?3")
          .bindBlob(1, salt.data(), salt.size())
          .bindBlob(2, hash.data(), hash.size())
          .bind(3, id)
          .run();
      Result<TokenInfo> info = LoadInfo(connection, id);
      transaction.commit();
      return NewToken{info.value(), secret};
    } catch (const std::runtime_error& e) {
      if (dynamic_cast<const SqliteError*>(&e) != nullptr) throw;
      return Error{ErrorCode::kStorage, e.what()};
    }
  });
}

Result<std::vector<TokenInfo>> ListTokens(Connection& connection) {
  return Guard([&]() -> Result<std::vector<TokenInfo>> {
    Statement s =
        connection.prepare(std::string("SELECT ") + kInfoColumns + " FROM api_tokens ORDER BY id");
    std::vector<TokenInfo> tokens;
    while (s.step()) tokens.push_back(ReadInfo(s));
    return tokens;
  });
}

Result<TokenInfo> GetToken(Connection& connection, std::int64_t id) {
  return Guard([&]() -> Result<TokenInfo> { return LoadInfo(connection, id); });
}

Result<TokenInfo> RevokeToken(Connection& connection, std::int64_t id, LastAdmin last_admin) {
  return Guard([&]() -> Result<TokenInfo> {
    Transaction transaction(connection);
    if (last_admin == LastAdmin::kKeep) {
      Statement others = connection.prepare(
          "SELECT (SELECT role = 'admin' AND revoked_at IS NULL FROM api_tokens WHERE id = ?1), "
          "(SELECT count(*) FROM api_tokens WHERE role = 'admin' AND revoked_at IS NULL AND "
          "id <> ?1)");
      others.bind(1, id);
      others.step();
      if (!others.isNull(0) && others.getInt64(0) == 1 && others.getInt64(1) == 0) {
        return Error{ErrorCode::kConflict,
                     "token " + std::to_string(id) +
                         " is the last active admin token; create another admin token before "
                         "revoking it (without one nobody could administer the server through "
                         "the API; `pintag token revoke` on the server's host still can)"};
      }
    }
    connection
        .prepare(std::string("UPDATE api_tokens SET revoked_at = ") + detail::kNowSql +
                 " WHERE id = ?1 AND revoked_at IS NULL")
        .bind(1, id)
        .run();
    auto info = LoadInfo(connection, id);
    if (info) transaction.commit();
    return info;
  });
}

bool HasTokenForm(std::string_view secret) {
  if (!secret.starts_with("pt_")) return false;
  const std::size_t underscore = secret.find('_', 3);
  if (underscore == std::string_view::npos || underscore == 3) return false;
  const std::string_view id = secret.substr(3, underscore - 3);
  const std::string_view random = secret.substr(underscore + 1);
  const auto base64url = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_';
  };
  return std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
         random.size() == (kSecretBytes * 8 + 5) / 6 &&
         std::all_of(random.begin(), random.end(), base64url);
}

Result<TokenInfo> VerifyToken(Connection& connection, std::string_view secret) {
  const Error denied{ErrorCode::kUnauthorized, "invalid or revoked token"};
  // pt_<id>_<secret>
  if (!secret.starts_with("pt_") || secret.size() > 100) return denied;
  const std::size_t underscore = secret.find('_', 3);
  if (underscore == std::string_view::npos) return denied;
  std::int64_t id = 0;
  const auto [end, error] = std::from_chars(secret.data() + 3, secret.data() + underscore, id);
  if (error != std::errc() || end != secret.data() + underscore) return denied;
  return Guard([&]() -> Result<TokenInfo> {
    Statement s = connection.prepare(std::string("SELECT ") + kInfoColumns +
                                     ", salt, secret_hash FROM api_tokens WHERE id = ?1");
    s.bind(1, id);
    if (!s.step()) return denied;
    const std::string salt = s.getBlob(5);
    const std::string stored = s.getBlob(6);
    const std::string hash = Sha256(salt, secret);
    if (stored.size() != hash.size() ||
        CRYPTO_memcmp(stored.data(), hash.data(), hash.size()) != 0) {
      return denied;
    }
    TokenInfo info = ReadInfo(s);
    if (info.revoked_at) return denied;
    return info;
  });
}

}  // namespace pintag::db
