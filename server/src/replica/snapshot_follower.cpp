// The one HTTP client in the server: cpp-httplib's, towards the primary.
#include "replica/snapshot_follower.hpp"

#include <httplib.h>
#include <sys/socket.h>

#include <charconv>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "pintag/server/log.hpp"
#include "replica/snapshot_publisher.hpp"
#include "replica/token_file.hpp"

namespace pintag::replica {

std::string RegistryETag(std::int64_t version, const std::string& epoch) {
  // Appended, not `"\"" + ...`: GCC 12 warns (-Wrestrict) about that concatenation wrongly.
  std::string tag = "\"";
  tag += std::to_string(version);
  tag += '-';
  tag += epoch;
  tag += '"';
  return tag;
}

namespace {

/// Whether a 503's problem body is the primary's "snapshots busy" (kBusyProblemType).
bool IsSnapshotsBusy(const std::string& body) {
  const nlohmann::json problem = nlohmann::json::parse(body, nullptr, /*allow_exceptions=*/false);
  return problem.is_object() && problem.contains("type") && problem["type"].is_string() &&
         problem["type"].get<std::string>() == SnapshotPublisher::kBusyProblemType;
}

/// What went wrong with a request to the primary, in words an operator can act on; cpp-httplib's
/// own names ("Connection", "Read") said little in a log line or the follow status.
std::string FailureText(httplib::Error error) {
  switch (error) {
    case httplib::Error::Connection:
      return "no connection could be made (is it running, at that address and port?)";
    case httplib::Error::ConnectionTimeout:
      return "the connection was not made within 5 s";
    case httplib::Error::Read:
      return "its answer broke off or did not come within the read timeout";
    case httplib::Error::Write:
      return "the request could not be sent (the connection was closed)";
    case httplib::Error::Canceled:
      return "the request was cancelled";
    default:
      return "the request failed (" + httplib::to_string(error) + ")";
  }
}

}  // namespace

SnapshotFollower::SnapshotFollower(FollowOptions options, OnInstalled on_installed)
    : options_(std::move(options)), on_installed_(std::move(on_installed)) {}

SnapshotFollower::~SnapshotFollower() {
  stopping_ = true;
  {
    const std::lock_guard lock(client_mutex_);
    // A request in flight has its socket shut: a blocked read returns at once (a connect in
    // progress first ends, within its 5 s timeout). One not yet in flight finds stopping_ set
    // where its socket is made.
    if (client_ != nullptr) client_->stop();
  }
  thread_.stop();
}

db::Result<std::optional<db::SnapshotInfo>> SnapshotFollower::fetch(
    std::optional<std::int64_t> have) {
  deferred_ = false;
  primary_answered_ = false;
  if (download_failures_ > 0 && std::chrono::steady_clock::now() < next_download_) {
    return download_error_;
  }
  httplib::Client client(options_.primary_url);
  if (!client.is_valid()) {
    return db::Error{db::ErrorCode::kInvalid, "not a primary URL: " + options_.primary_url};
  }
  client.set_connection_timeout(std::chrono::seconds(5));
  client.set_read_timeout(options_.timeout);
  client.set_socket_options([this](socket_t socket) {
    if (stopping_) ::shutdown(socket, SHUT_RDWR);
  });
  {
    const std::lock_guard lock(client_mutex_);
    if (stopping_) return db::Error{db::ErrorCode::kBusy, "stopping"};
    client_ = &client;
  }
  struct Unregister {
    SnapshotFollower* follower;
    ~Unregister() {
      const std::lock_guard lock(follower->client_mutex_);
      follower->client_ = nullptr;
    }
  } unregister{this};
  httplib::Headers headers = {{"Authorization", "Bearer " + pollToken()}};
  // The ETag is known for a snapshot fetched in this run; one found on disk at start is fetched
  // once more, since the primary may have been restored since it was written.
  const bool holds_installed = have && *have == installed_version_ && !installed_etag_.empty();
  std::string none_match = holds_installed ? installed_etag_ : "";
  if (!refused_etag_.empty()) none_match += (none_match.empty() ? "" : ", ") + refused_etag_;
  if (!none_match.empty()) headers.emplace("If-None-Match", none_match);
  // The body is received here, not by the client, so that a body past max_bytes is refused
  // as it arrives (a primary, or whatever answers at its URL, sent 2 GB and got it all held).
  std::string body;
  bool too_large = false;
  const httplib::Result answer = client.Get(
      "/api/v1/registry/snapshot", headers,
      [&](const httplib::Response& response) {
        // An answer, whatever is made of it (a body refused below for its size included).
        primary_answered_ = response.status == 200 || response.status == 304;
        const std::string length = response.get_header_value("Content-Length");
        std::uint64_t declared = 0;
        const auto [end, error] =
            std::from_chars(length.data(), length.data() + length.size(), declared);
        too_large = error == std::errc::result_out_of_range ||
                    (error == std::errc() && declared > options_.max_bytes);
        return !too_large;
      },
      [&](const char* data, std::size_t size) {
        too_large = body.size() + size > options_.max_bytes;
        if (!too_large) body.append(data, size);
        return !too_large;
      });
  if (too_large) {
    return downloadWasted({db::ErrorCode::kStorage,
                           "primary " + options_.primary_url + " sent a snapshot of more than " +
                               std::to_string(options_.max_bytes >> 20) + " MiB; refused"});
  }
  if (!answer) {
    return db::Error{db::ErrorCode::kBusy, "primary " + options_.primary_url +
                                               " did not answer: " + FailureText(answer.error())};
  }
  primary_answered_ = answer->status == 200 || answer->status == 304;
  if (answer->status == 304) {
    if (!refused_etag_.empty() && answer->get_header_value("ETag") == refused_etag_) {
      return refused_error_;
    }
    return std::optional<db::SnapshotInfo>{};
  }
  // The primary is sending as many snapshots as it will at once: asked again at the next poll,
  // neither an answer nor an error (it would log and mark the follower failing after every
  // change). Only that 503 is: a primary whose database stays busy or gone is a failure.
  if (answer->status == 503 && IsSnapshotsBusy(body)) {
    deferred_ = true;
    return std::optional<db::SnapshotInfo>{};
  }
  if (answer->status != 200) {
    return db::Error{db::ErrorCode::kStorage, "primary " + options_.primary_url + " answered " +
                                                  std::to_string(answer->status) + ": " +
                                                  body.substr(0, 300)};
  }
  const std::string etag = answer->get_header_value("ETag");
  // A primary (or a proxy) that ignores If-None-Match sends what is already served.
  if (holds_installed && etag == installed_etag_) return std::optional<db::SnapshotInfo>{};
  db::Result<db::SnapshotInfo> installed = db::InstallSnapshot(body, options_.path);
  if (!installed) {
    // A refusal for what the snapshot holds stands until the primary serves another; a download
    // that did not arrive whole is fetched again.
    if (installed.error().code == db::ErrorCode::kConflict && !etag.empty()) {
      refused_etag_ = etag;
      refused_error_ = installed.error();
      return installed.error();
    }
    return downloadWasted(installed.error());
  }
  download_failures_ = 0;
  refused_etag_.clear();
  installed_etag_ = etag;
  installed_version_ = installed->registry_version;
  return std::optional<db::SnapshotInfo>{*installed};
}

db::Error SnapshotFollower::downloadWasted(db::Error error) {
  // 1, 2, 4, … s, at most kMaxDownloadDelay.
  const std::chrono::seconds delay =
      std::min(kMaxDownloadDelay, std::chrono::seconds(1LL << std::min(download_failures_, 6)));
  ++download_failures_;
  next_download_ = std::chrono::steady_clock::now() + delay;
  // The same words each time, so that a failure that repeats is logged once.
  error.message += " (downloaded again after 1 s, 2 s, 4 s … at most a minute)";
  download_error_ = error;
  return error;
}

bool SnapshotFollower::setToken(std::string token) {
  const std::lock_guard lock(client_mutex_);
  const bool changed = token != options_.token;
  options_.token = std::move(token);
  // The file may have changed since it was read: the next poll looks at it (stat, then read).
  token_file_seen_.reset();
  return changed;
}

std::string SnapshotFollower::pollToken() {
  const std::lock_guard lock(client_mutex_);
  if (options_.token_file.empty()) return options_.token;
  // One stat a poll. A file being rewritten may be read half-written (a write in place): read
  // again at the next poll, since its identity changes once more when it is whole.
  const std::optional<FileIdentity> now = IdentifyFile(options_.token_file);
  if (!now || now == token_file_seen_) return options_.token;
  token_file_seen_ = now;
  std::optional<std::string> token = ReadTokenFile(options_.token_file);
  if (!token) {
    // Once for each state of the file (another user's 0600 file, an empty one).
    server::LogEvent("cannot read a replica token from " + options_.token_file +
                         ", which changed; the one in use is kept",
                     /*warning=*/true);
  } else if (*token != options_.token) {
    options_.token = std::move(*token);
    server::LogEvent("the replica token was read again from " + options_.token_file +
                     ", which changed");
  }
  return options_.token;
}

void SnapshotFollower::start(Have have, std::chrono::milliseconds interval,
                             std::shared_ptr<FollowStatus> status) {
  thread_.start(interval, [this, have = std::move(have), status = std::move(status),
                           last_error = std::string()]() mutable {
    // An exception must not leave this thread (std::terminate would end the server).
    db::Result<std::optional<db::SnapshotInfo>> fetched = std::optional<db::SnapshotInfo>{};
    try {
      fetched = fetch(have());
    } catch (const std::exception& e) {
      fetched = db::Error{db::ErrorCode::kStorage, std::string("following failed: ") + e.what()};
    }
    if (stopping_ || deferred_) return;  // a cancelled download, or a primary that said "later"
    if (status) {
      if (fetched) {
        status->succeeded();
      } else {
        status->failed(fetched.error().message, primary_answered_);
      }
    }
    if (!fetched) {
      if (fetched.error().message != last_error) {
        server::LogEvent("following " + options_.primary_url + ": " + fetched.error().message,
                         /*warning=*/true);
      }
      last_error = fetched.error().message;
      return;
    }
    last_error.clear();
    if (*fetched) on_installed_(**fetched);
  });
}

}  // namespace pintag::replica
