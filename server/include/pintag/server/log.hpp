#pragma once
// The server log, on stderr through spdlog: one access line per request, and the events an
// operator must see (unexpected exceptions with their request id, database failures, snapshots).
// stdout stays for the start banner (its URL and first admin token). Thread-safe.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace pintag::server {

enum class LogFormat {
  kText,  ///< one human-readable line: time, level, then key=value pairs
  kJson,  ///< one JSON object a line (for log shippers)
};

/// "text" or "json"; nothing for anything else.
std::optional<LogFormat> ParseLogFormat(std::string_view text);

/// Chooses the format of every later line; text until called. Call before serving.
void ConfigureLog(LogFormat format);
/// The format chosen (text until ConfigureLog).
LogFormat ConfiguredLogFormat();

/// Turns the access lines off (or on again): the fuzz targets answer millions of requests, and
/// their reports must not drown. Errors and events are still written.
void SetAccessLogEnabled(bool enabled);

/// One answered request.
struct AccessRecord {
  std::string_view request_id;
  std::string_view client;  ///< remote address, or the one a trusted proxy forwarded for
  std::string_view proxy;   ///< the trusted proxy's address when `client` came from its header
  std::string_view method;
  std::string_view path;  ///< without the query: query values may hold secrets
  int status = 0;
  std::size_t bytes = 0;       ///< response body bytes
  double seconds = 0;          ///< from the request's head having arrived to its answer written
  std::string_view principal;  ///< the token id, or empty for open routes
  bool cut_off = false;        ///< the answer did not all reach the client (it went away)
  bool routine = false;        ///< one of the route's routine_statuses: throttled per client
};
void LogAccess(const AccessRecord& record);

/// A failure the client was not told the details of (a 500), with the request it happened in.
void LogRequestError(std::string_view request_id, std::string_view message);

/// Anything else worth an operator's attention (`warning` raises the level from info).
void LogEvent(std::string_view message, bool warning = false);
/// What ends the process (a port taken, a database that cannot be opened), at level error.
void LogFatal(std::string_view message);

/// A request id from the client's X-Request-Id when it is sane (1 … 128 of A-Z a-z 0-9 - _ . :),
/// else a new random one (32 hex digits).
std::string RequestIdFrom(std::optional<std::string_view> client_value);

}  // namespace pintag::server
