// The one HTTP client in the server: cpp-httplib's, towards the primary.
#include "replica/snapshot_follower.hpp"

#include <httplib.h>

#include <iostream>

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

SnapshotFollower::SnapshotFollower(FollowOptions options, OnInstalled on_installed)
    : options_(std::move(options)), on_installed_(std::move(on_installed)) {}

db::Result<std::optional<db::SnapshotInfo>> SnapshotFollower::fetch(
    std::optional<std::int64_t> have) {
  httplib::Client client(options_.primary_url);
  if (!client.is_valid()) {
    return db::Error{db::ErrorCode::kInvalid, "not a primary URL: " + options_.primary_url};
  }
  client.set_connection_timeout(std::chrono::seconds(5));
  client.set_read_timeout(options_.timeout);
  httplib::Headers headers = {{"Authorization", "Bearer " + options_.token}};
  // The ETag is known for a snapshot fetched in this run; one found on disk at start is fetched
  // once more, since the primary may have been restored since it was written.
  const bool holds_installed = have && *have == installed_version_ && !installed_etag_.empty();
  if (holds_installed) headers.emplace("If-None-Match", installed_etag_);
  const httplib::Result answer = client.Get("/api/v1/registry/snapshot", headers);
  if (!answer) {
    return db::Error{db::ErrorCode::kBusy, "primary " + options_.primary_url + " did not answer: " +
                                               httplib::to_string(answer.error())};
  }
  if (answer->status == 304) return std::optional<db::SnapshotInfo>{};
  if (answer->status != 200) {
    return db::Error{db::ErrorCode::kStorage, "primary " + options_.primary_url + " answered " +
                                                  std::to_string(answer->status) + ": " +
                                                  answer->body.substr(0, 300)};
  }
  const std::string etag = answer->get_header_value("ETag");
  // A primary (or a proxy) that ignores If-None-Match sends what is already served.
  if (holds_installed && etag == installed_etag_) return std::optional<db::SnapshotInfo>{};
  db::Result<db::SnapshotInfo> installed = db::InstallSnapshot(answer->body, options_.path);
  if (!installed) return installed.error();
  installed_etag_ = etag;
  installed_version_ = installed->registry_version;
  return std::optional<db::SnapshotInfo>{*installed};
}

void SnapshotFollower::start(Have have, std::chrono::milliseconds interval) {
  thread_.start(interval, [this, have = std::move(have), last_error = std::string()]() mutable {
    const auto fetched = fetch(have());
    if (!fetched) {
      if (fetched.error().message != last_error) {
        std::cerr << "pintag serve: following " << options_.primary_url << ": "
                  << fetched.error().message << "\n";
      }
      last_error = fetched.error().message;
      return;
    }
    last_error.clear();
    if (*fetched) on_installed_(**fetched);
  });
}

}  // namespace pintag::replica
