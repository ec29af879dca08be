// spdlog behind log.hpp: one stderr logger; the format decides the pattern and how the fields of
// a line are written. Only this file includes spdlog.

#include "pintag/server/log.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <utility>
#include <vector>

#include "pintag/server/routine_access_throttle.hpp"

namespace pintag::server {
namespace {

using Field = std::pair<std::string_view, nlohmann::json>;

std::atomic<LogFormat> g_format{LogFormat::kText};
std::atomic<bool> g_access_enabled{true};

// Time in UTC with milliseconds, as an operator greps it and a shipper parses it.
constexpr const char* kTextPattern = "%Y-%m-%dT%H:%M:%S.%eZ %l %v";
constexpr const char* kJsonPattern = R"({"time":"%Y-%m-%dT%H:%M:%S.%eZ","level":"%l",%v})";

spdlog::logger& Logger() {
  static const std::shared_ptr<spdlog::logger> logger = [] {
    auto made = std::make_shared<spdlog::logger>("pintag",
                                                 std::make_shared<spdlog::sinks::stderr_sink_mt>());
    made->set_pattern(kTextPattern, spdlog::pattern_time_type::utc);
    made->flush_on(spdlog::level::info);  // a killed server has written every line it logged
    return made;
  }();
  return *logger;
}

std::string Dump(const nlohmann::json& value) {
  // Paths and messages may hold invalid UTF-8: replace it rather than throw.
  return value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

/// text: `event key=value …` with strings quoted only when they need it; json: the fields of
/// the object the pattern opens.
std::string Render(std::string_view event, const std::vector<Field>& fields) {
  std::string line;
  if (g_format.load() == LogFormat::kJson) {
    nlohmann::json object = nlohmann::json::object();
    object["event"] = event;
    for (const auto& [name, value] : fields) object[std::string(name)] = value;
    line = Dump(object);
    return line.substr(1, line.size() - 2);  // the pattern writes the braces
  }
  line = event;
  for (const auto& [name, value] : fields) {
    line += ' ';
    line += name;
    line += '=';
    if (value.is_string()) {
      const std::string& text = value.get_ref<const std::string&>();
      const bool plain =
          !text.empty() && text.find_first_of(" \"=\\") == std::string::npos &&
          std::all_of(text.begin(), text.end(), [](char c) {
            return static_cast<unsigned char>(c) > 0x20 && static_cast<unsigned char>(c) < 0x7f;
          });
      line += plain ? text : Dump(value);
    } else {
      line += Dump(value);
    }
  }
  return line;
}

bool SaneRequestId(std::string_view id) {
  if (id.empty() || id.size() > 128) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
           c == '_' || c == '.' || c == ':';
  });
}

}  // namespace

std::optional<LogFormat> ParseLogFormat(std::string_view text) {
  if (text == "text") return LogFormat::kText;
  if (text == "json") return LogFormat::kJson;
  return std::nullopt;
}

void ConfigureLog(LogFormat format) {
  g_format = format;
  Logger().set_pattern(format == LogFormat::kJson ? kJsonPattern : kTextPattern,
                       spdlog::pattern_time_type::utc);
}

LogFormat ConfiguredLogFormat() {
  return g_format.load();
}

void SetAccessLogEnabled(bool enabled) {
  g_access_enabled = enabled;
}

void LogAccess(const AccessRecord& r) {
  if (!g_access_enabled) return;
  std::size_t left_out = 0;
  if (r.routine) {
    // Never destroyed: a worker may still log while the process exits.
    static RoutineAccessThrottle& throttle = *new RoutineAccessThrottle;
    std::string kind;
    for (const std::string_view part : {r.client, r.principal, r.method, r.path}) {
      kind += part;
      kind += '\n';
    }
    kind += std::to_string(r.status);
    const std::optional<std::size_t> admitted = throttle.admit(kind);
    if (!admitted) return;
    left_out = *admitted;
  }
  std::vector<Field> fields = {{"id", std::string(r.request_id)},
                               {"client", std::string(r.client)},
                               {"method", std::string(r.method)},
                               {"path", std::string(r.path)},
                               {"status", r.status},
                               {"bytes", r.bytes},
                               {"ms", std::round(r.seconds * 1e6) / 1e3}};
  if (!r.principal.empty()) fields.emplace_back("token", std::string(r.principal));
  if (!r.proxy.empty()) fields.emplace_back("proxy", std::string(r.proxy));
  // The status is what the server answered; the client may not have received it.
  if (r.cut_off) fields.emplace_back("cut_off", true);
  // Routine answers of this kind whose lines were left out since its last one.
  if (left_out > 0) fields.emplace_back("left_out", left_out);
  Logger().info(Render("access", fields));
}

void LogRequestError(std::string_view request_id, std::string_view message) {
  Logger().error(
      Render("error", {{"id", std::string(request_id)}, {"message", std::string(message)}}));
}

void LogEvent(std::string_view message, bool warning) {
  const std::string line = Render("event", {{"message", std::string(message)}});
  if (warning) {
    Logger().warn(line);
  } else {
    Logger().info(line);
  }
}

void LogFatal(std::string_view message) {
  Logger().error(Render("event", {{"message", std::string(message)}}));
}

std::string RequestIdFrom(std::optional<std::string_view> client_value) {
  if (client_value && SaneRequestId(*client_value)) return std::string(*client_value);
  thread_local std::mt19937_64 random{std::random_device{}()};
  char text[33];
  std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(random()),
                static_cast<unsigned long long>(random()));
  return text;
}

}  // namespace pintag::server
