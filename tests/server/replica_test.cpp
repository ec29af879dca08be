// Read-only replicas (`pintag serve --read-only`, `--follow`) against a real primary: what they
// serve and refuse, where their scans go, how they take a newer snapshot while requests are in
// flight, and what they do with a file that is not one.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <thread>

#include "label_photo.hpp"
#include "pintag/codec/key_allocation.hpp"
#include "pintag/db/database.hpp"
#include "pintag/db/registry.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/test/loopback_socket.hpp"
#include "pintag/test/test_office.hpp"
#include "replica/snapshot_follower.hpp"
#include "replica_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

json Body(const httplib::Result& r) {
  if (!r) return {};
  const json body = json::parse(r->body, nullptr, false);
  return body.is_discarded() ? json() : body;
}

// An answer's status, −1 when there was none: a dropped connection or a timeout fails the
// comparison instead of crashing the test (and losing the servers' stderr the fixture prints).
int StatusOf(const httplib::Result& r) {
  return r ? r->status : -1;
}

// A client of a server on loopback that waits up to 30 s for an answer.
httplib::Client LoopbackClient(int port) {
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(30, 0);
  return client;
}

// Polls `done` every 50 ms until it holds or `limit` passes; whether it holds. Polled, not timed:
// the limit only stops a broken server from hanging the test.
bool WaitUntil(const std::function<bool()>& done,
               std::chrono::seconds limit = std::chrono::seconds(60)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

// Waits for GET `path` to answer `status`; the last status seen.
int WaitForStatus(httplib::Client& client, const std::string& path, int status) {
  int seen = 0;
  WaitUntil([&] { return (seen = StatusOf(client.Get(path))) == status; });
  return seen;
}

std::int64_t CountRows(const std::string& path, const std::string& table) {
  db::Connection connection(path, {.create = false, .read_only = true});
  return connection.queryInt64("SELECT count(*) FROM " + table);
}

// Lookups from 8 clients at once on `port`, so that its pool opens new connections: how many of
// the 40 were answered 200.
int LookupsFromManyClients(int port) {
  return CallsRightFromConcurrentClients(port, 8, 5, [](httplib::Client& client) {
    const auto r = client.Get("/api/v1/pincodes/560001");
    return r && r->status == 200;
  });
}

using pintag::test::TestOffice;

// The files beside `snapshot` whose names start with its name and ".serving-".
std::set<std::string> ServingFiles(const std::string& snapshot) {
  const std::filesystem::path path(snapshot);
  const std::string prefix = path.filename().string() + ".serving-";
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(path.parent_path())) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) == 0) names.insert(name);
  }
  return names;
}

TEST_F(ReplicaSetTest, AFollowerServesReadsAndRefusesWritesNamingThePrimary) {
  ServerProcess& replica = startFollower(0);
  ASSERT_TRUE(replica.ok());
  httplib::Client client("127.0.0.1", replica.port());
  client.set_read_timeout(30, 0);

  const json status = Body(client.Get("/api/v1/registry"));
  EXPECT_EQ(status["role"], "replica");
  EXPECT_EQ(status["primary"], primaryUrl());
  EXPECT_EQ(status["registry_version"], RegistryVersionAt(primary_->port()));

  const auto lookup = client.Get("/api/v1/pincodes/110001");
  ASSERT_TRUE(lookup);
  EXPECT_EQ(lookup->status, 200);
  EXPECT_EQ(Body(lookup)["key"], 11684);
  const auto label = client.Get("/api/v1/labels/110001.png?dpi=100", Auth(counter_token_));
  ASSERT_TRUE(label);
  EXPECT_EQ(label->status, 200);
  EXPECT_EQ(label->get_header_value("Content-Type"), "image/png");
  const auto batch = client.Post("/api/v1/labels", Auth(counter_token_),
                                 R"({"pincodes": ["110001", "560001"]})", "application/json");
  ASSERT_TRUE(batch);
  EXPECT_EQ(batch->status, 200);

  // Every registry write is refused before any token is asked for, naming the primary.
  const std::vector<std::pair<std::string, std::string>> writes = {
      {"POST", "/api/v1/pincodes"},
      {"POST", "/api/v1/pincodes/110001/retire"},
      {"PUT", "/api/v1/sortplans/hub"},
      {"POST", "/api/v1/tokens"},
      {"DELETE", "/api/v1/tokens/1"}};
  for (const auto& [method, path] : writes) {
    for (const httplib::Headers& headers : {httplib::Headers{}, Auth(admin_token_)}) {
      httplib::Request request;
      request.method = method;
      request.path = path;
      request.headers = headers;
      request.body = R"({"pincode": "999001"})";
      request.set_header("Content-Type", "application/json");
      const auto r = client.send(request);
      ASSERT_TRUE(r) << method << " " << path;
      EXPECT_EQ(r->status, 403) << method << " " << path << ": " << r->body;
      EXPECT_EQ(r->get_header_value("Content-Type"), "application/problem+json");
      const json problem = Body(r);
      EXPECT_EQ(problem["title"], "Read-Only Replica");
      EXPECT_NE(problem.value("detail", "").find(primaryUrl()), std::string::npos) << r->body;
    }
  }
  // Refused before the body is read: announced and never sent, it is not waited for.
  const std::string unsent =
      "POST /api/v1/pincodes HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: multipart/form-data; "
      "boundary=x\r\nContent-Length: 20000000\r\n\r\n";
  const std::string answer = test::SendRaw(replica.port(), unsent, 30);
  EXPECT_EQ(answer.rfind("HTTP/1.1 403", 0), 0U) << answer.substr(0, 300);
  EXPECT_NE(answer.find("Read-Only Replica"), std::string::npos) << answer.substr(0, 300);
  // The primary was not changed by any of them.
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/pincodes/999001")), 404);
  EXPECT_EQ(Body(primary.Get("/api/v1/pincodes/110001"))["status"], "active");
}

TEST_F(ReplicaSetTest, AReplicaLogsScansInItsOwnFileAndTheSnapshotStaysUntouched) {
  ServerProcess& replica = startFollower(0);
  ASSERT_TRUE(replica.ok());
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  const Photo photo = PhotographLabel(primary, Auth(counter_token_), "110001", 20,
                                      scene::Camera{700, 700, 400, 300, 800, 600});
  ASSERT_FALSE(photo.jpeg.empty());
  httplib::Client client("127.0.0.1", replica.port());
  client.set_read_timeout(30, 0);
  for (int i = 0; i < 3; ++i) {
    const auto r = client.Post("/api/v1/detect", Auth(scanner_token_), photo.jpeg, "image/jpeg");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    const json out = Body(r);
    ASSERT_EQ(out["tags"].size(), 1U) << r->body;
    EXPECT_EQ(out["tags"][0]["pincode"], "110001");
    // The answer names the registry the replica resolved it in: the snapshot it serves.
    EXPECT_EQ(out["registry_version"], Body(client.Get("/api/v1/registry"))["registry_version"]);
  }
  EXPECT_EQ(ScanRowsOnceThereAre(replicaScanLog(0), 3), 3);
  EXPECT_EQ(CountRows(replicaDb(0), "scan_log"), 0);
  EXPECT_EQ(CountRows(primary_db_, "scan_log"), 0);
}

// A directory CSV of one new office and pincode (799996), for `pintag import`.
constexpr const char* kOneNewOfficeCsv =
    "circlename,regionname,divisionname,officename,pincode,officetype,delivery,district,"
    "statename,latitude,longitude\n"
    "X Circle,X,X,Testpur S.O,799996,SO,Delivery,Testdist,Teststate,12.0,77.0\n";

// `pintag import --db` a running replica's snapshot changed that replica's registry alone (a key
// the primary does not have, given out again there) and stuck it: it refused every snapshot after,
// since its file was now in WAL mode. Every command that writes refuses such a file, unchanged.
TEST_F(ReplicaSetTest, CommandsThatWriteRefuseTheSnapshotARunningReplicaServes) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  const std::string before = ReadFile(snapshot);
  const std::string csv = WriteFile(dir_.file("one.csv"), kOneNewOfficeCsv);
  const std::vector<std::string> writes = {"import " + csv + " --db " + snapshot,
                                           "token create --role counter --db " + snapshot,
                                           "token revoke 1 --db " + snapshot};
  for (const std::string& command : writes) {
    const CommandResult refused = RunPintag(command);
    EXPECT_EQ(refused.status, 1) << command << ": " << refused.out;
    EXPECT_NE(refused.out.find(snapshot + " is the snapshot a running replica serves"),
              std::string::npos)
        << refused.out;
  }
  EXPECT_EQ(ReadFile(snapshot), before);
  EXPECT_FALSE(std::filesystem::exists(snapshot + "-wal"));
  EXPECT_EQ(StatusOf(LoopbackClient(replica.port()).Get("/readyz")), 200);
  // Reading it is no harm (`keys lookup` opens it read-only). Once the replica has stopped, the
  // file is anyone's again: a restore copies a replica's file to a primary.
  EXPECT_EQ(RunPintag("keys lookup 110001 --db " + snapshot).status, 0);
  EXPECT_EQ(replica.stop(SIGTERM, 30), 0);
  const CommandResult imported = RunPintag("import " + csv + " --db " + snapshot);
  EXPECT_EQ(imported.status, 0) << imported.out;
}

// A primary restored as SCALING.md says, from a replica's file, but over a database that stopped
// uncleanly: the write-ahead log left beside it was applied by SQLite to the copied-in file
// (undoing the restore, or damaging the file while /readyz said ready). Refused until it is gone.
TEST_F(ReplicaSetTest, ARestoredFileIsNotOpenedUnderTheLogOfTheDatabaseItReplaced) {
  const std::string snapshot = publishTo("served.db");
  const std::string live = dir_.file("restored.db");
  std::filesystem::copy_file(snapshot, live);
  const std::string copied = ReadFile(live);
  // The replaced database's log: its contents are not looked at, only that it is there.
  WriteFile(live + "-wal", std::string(4096, 'w'));
  const std::string csv = WriteFile(dir_.file("one.csv"), kOneNewOfficeCsv);
  const std::vector<std::string> opens = {"token create --role counter --db " + live,
                                          "import " + csv + " --db " + live,
                                          "serve --port 0 --bind 127.0.0.1 --db " + live};
  const std::string says = "database " + live +
                           " is in rollback-journal mode (a snapshot or backup copied in), but " +
                           live + "-wal";
  const std::string pintag = "timeout 30 " + PintagExe() + " ";
  for (const std::string& command : opens) {
    std::string line = pintag;
    line.append(command).append(" 2>&1");
    const CommandResult refused = RunShell(line);
    EXPECT_EQ(refused.status, 1) << command << ": " << refused.out;
    EXPECT_NE(refused.out.find(says), std::string::npos) << refused.out;
  }
  EXPECT_EQ(ReadFile(live), copied);
  EXPECT_EQ(ReadFile(live + "-wal"), std::string(4096, 'w'));
  std::filesystem::remove(live + "-wal");
  std::filesystem::remove(live + "-shm");
  const CommandResult made = RunPintag("token create --role counter --db " + live);
  EXPECT_EQ(made.status, 0) << made.out;
}

// A scan log that cannot be written loses scans while every answer stays 200: the count says so.
TEST_F(ReplicaSetTest, ScansTheLogCannotKeepAreCounted) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  // Overwritten in place while the replica holds it open (a replica refuses to start on junk).
  WriteFile(replicaScanLog(0), std::string(1 << 16, 'x'));
  httplib::Client primary = LoopbackClient(primary_->port());
  const Photo photo = PhotographLabel(primary, Auth(counter_token_), "110001", 20,
                                      scene::Camera{700, 700, 400, 300, 800, 600});
  ASSERT_FALSE(photo.jpeg.empty());
  httplib::Client client = LoopbackClient(replica.port());
  for (int i = 0; i < 2; ++i) {
    const auto r = client.Post("/api/v1/detect", Auth(scanner_token_), photo.jpeg, "image/jpeg");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;
  }
  // Counted by the log's thread once it gives the scans up (their answers may come first).
  std::string metrics;
  WaitUntil([&] {
    const auto page = client.Get("/metrics");
    metrics = page ? page->body : std::string();
    return metrics.find("\npintag_scan_log_failures_total 2\n") != std::string::npos;
  });
  EXPECT_NE(metrics.find("\npintag_scan_log_failures_total 2\n"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("\npintag_scans_total 2\n"), std::string::npos);
  EXPECT_NE(stderrOf("replica-0").find("scan log: "), std::string::npos);
}

/// The value of `series` (a metric's name and its labels, as /metrics writes them) on the
/// server's /metrics, or -1 when it is not there.
double MetricAt(httplib::Client& client, const std::string& series) {
  const auto page = client.Get("/metrics");
  if (!page || page->status != 200) return -1;
  const std::string line_start = "\n" + series + " ";
  const std::size_t at = page->body.find(line_start);
  return at == std::string::npos ? -1 : std::stod(page->body.substr(at + line_start.size()));
}

/// The series counting a primary's answers to snapshot polls with `status`.
std::string SnapshotAnswers(int status) {
  return R"(pintag_http_requests_total{route="/api/v1/registry/snapshot",method="GET",status=")" +
         std::to_string(status) + R"("})";
}

// The registry version each server serves is a gauge (since 2026-12-08), so that an alert can
// compare a replica's with its primary's: before, only GET /api/v1/registry said it.
TEST_F(ReplicaSetTest, AFollowerServesAPincodeAddedOnThePrimary) {
  ServerProcess& replica = startFollower(0);
  ASSERT_TRUE(replica.ok());
  httplib::Client client("127.0.0.1", replica.port());
  client.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(client.Get("/api/v1/pincodes/999123")), 404);
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  const std::int64_t before = RegistryVersionAt(primary_->port());
  EXPECT_EQ(MetricAt(client, "pintag_registry_version"), static_cast<double>(before));
  addPincode(primary, "999123");
  ASSERT_EQ(WaitForStatus(client, "/api/v1/pincodes/999123", 200), 200) << stderrOf("replica-0");
  const std::int64_t after = RegistryVersionAt(primary_->port());
  EXPECT_GT(after, before);
  EXPECT_EQ(RegistryVersionAt(replica.port()), after);
  EXPECT_EQ(MetricAt(client, "pintag_registry_version"), static_cast<double>(after));
  EXPECT_EQ(MetricAt(primary, "pintag_registry_version"), static_cast<double>(after));
  // The replica has it, so the primary published it.
  EXPECT_EQ(MetricAt(primary, "pintag_snapshot_published_version"), static_cast<double>(after));
  EXPECT_EQ(MetricAt(client, "pintag_snapshot_published_version"), -1)
      << "a replica publishes none";
}

TEST_F(ReplicaSetTest, AFollowerWaitingForItsFirstSnapshotOutlivesSigHup) {
  // No primary to follow: the follower waits for its first snapshot and never serves.
  ASSERT_EQ(primary_->stop(SIGTERM, 30), 0);
  ServerProcess follower({"--db", replicaDb(0), "--follow", primaryUrl(), "--follow-token-file",
                          dir_.file("replica.token"), "--follow-interval-ms", "100"},
                         dir_.file("replica-0.err"), /*timeout_s=*/1);
  ASSERT_FALSE(follower.ok());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (stderrOf("replica-0").find("waiting for a snapshot") == std::string::npos &&
         follower.running() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_NE(stderrOf("replica-0").find("waiting for a snapshot"), std::string::npos);
  // A reload asked for while it waits (logrotate, an operator) must not end it: with SIGHUP's
  // default action it was gone at once. It goes on waiting, and SIGTERM still stops it.
  follower.signal(SIGHUP);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_TRUE(follower.running());
  EXPECT_EQ(follower.stop(SIGTERM, 30), 128 + SIGTERM);
}

// With --log-format json, every line a server writes on stderr is one JSON object, so a log
// pipeline parses them all. A primary's publishing and a follower's following were plain text
// among them, the line saying the primary stopped answering included.
TEST_F(ReplicaSetTest, WithJsonLogsEveryLineOfAPrimaryAndItsFollowerIsAnObject) {
  ASSERT_EQ(primary_->stop(SIGTERM, 30), 0);
  primary_ = std::make_unique<ServerProcess>(
      std::vector<std::string>{"--db", primary_db_, "--log-format", "json", "--snapshot",
                               dir_.file("published.db")},
      dir_.file("primary-json.err"));
  ASSERT_TRUE(primary_->ok()) << stderrOf("primary-json");
  ServerProcess follower({"--db", replicaDb(0), "--follow", primaryUrl(), "--follow-token-file",
                          dir_.file("replica.token"), "--follow-interval-ms", "100", "--log-format",
                          "json", "--scan-log", replicaScanLog(0)},
                         dir_.file("replica-0.err"));
  ASSERT_TRUE(follower.ok()) << stderrOf("replica-0");
  ASSERT_EQ(primary_->stop(SIGTERM, 30), 0);
  ASSERT_TRUE(
      WaitUntil([&] { return stderrOf("replica-0").find("following") != std::string::npos; }));
  ASSERT_EQ(follower.stop(SIGTERM, 30), 0);

  const auto messages = [&](const std::string& name) {
    std::vector<std::string> events;
    std::istringstream lines(stderrOf(name));
    for (std::string line; std::getline(lines, line);) {
      const nlohmann::json object = nlohmann::json::parse(line, nullptr, false);
      EXPECT_TRUE(object.is_object()) << name << ": " << line;
      if (object.is_object() && object.value("event", "") == "event") {
        events.push_back(object.value("message", ""));
      }
    }
    return events;
  };
  const auto holds = [](const std::vector<std::string>& events, const std::string& start) {
    return std::any_of(events.begin(), events.end(),
                       [&](const std::string& m) { return m.rfind(start, 0) == 0; });
  };
  const std::vector<std::string> primary = messages("primary-json");
  EXPECT_TRUE(holds(primary, "published snapshot " + dir_.file("published.db")));
  const std::vector<std::string> replica = messages("replica-0");
  EXPECT_TRUE(holds(replica, "following " + primaryUrl() + ": ")) << stderrOf("replica-0");
}

TEST_F(ReplicaSetTest, TheSnapshotRouteAnswersReplicaTokensWithETagsAndOnlyThem) {
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/registry/snapshot")), 401);
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/registry/snapshot", Auth(scanner_token_))), 403);
  // A replica token opens nothing else.
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/labels/110001.pdf", Auth(replica_token_))), 403);
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/tokens", Auth(replica_token_))), 403);

  const auto full = primary.Get("/api/v1/registry/snapshot", Auth(replica_token_));
  ASSERT_TRUE(full);
  ASSERT_EQ(full->status, 200);
  EXPECT_EQ(full->get_header_value("Content-Type"), "application/vnd.sqlite3");
  // "<version>-<the primary run's epoch>"
  const std::string etag = full->get_header_value("ETag");
  const std::string version_part = "\"" + std::to_string(RegistryVersionAt(primary_->port())) + "-";
  EXPECT_EQ(etag.substr(0, version_part.size()), version_part) << etag;
  EXPECT_EQ(etag.back(), '"');
  const std::string copy = WriteFile(dir_.file("downloaded.db"), full->body);
  const auto verified = db::VerifySnapshot(copy);
  ASSERT_TRUE(verified.ok()) << verified.error().message;
  EXPECT_EQ(etag.substr(0, version_part.size()),
            "\"" + std::to_string(verified->registry_version) + "-");

  httplib::Headers current = Auth(replica_token_);
  current.emplace("If-None-Match", etag);
  const auto unchanged = primary.Get("/api/v1/registry/snapshot", current);
  ASSERT_TRUE(unchanged);
  EXPECT_EQ(unchanged->status, 304);
  EXPECT_TRUE(unchanged->body.empty());
  // As RFC 9110 reads the header: a list naming it, a weak form of it, or `*` is 304 too.
  for (const std::string& header : {"\"other\", " + etag, "W/" + etag, std::string("*")}) {
    httplib::Headers listed = Auth(replica_token_);
    listed.emplace("If-None-Match", header);
    EXPECT_EQ(StatusOf(primary.Get("/api/v1/registry/snapshot", listed)), 304) << header;
  }
  // The ETag followers before the epoch send, the version alone: current for them too.
  httplib::Headers version_only = Auth(replica_token_);
  version_only.emplace("If-None-Match", etag.substr(0, version_part.size() - 1) + "\"");
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/registry/snapshot", version_only)), 304);
  httplib::Headers other = Auth(replica_token_);
  other.emplace("If-None-Match", "\"other\", W/\"another\"");
  EXPECT_EQ(StatusOf(primary.Get("/api/v1/registry/snapshot", other)), 200);

  addPincode(primary, "999124");
  const auto changed = primary.Get("/api/v1/registry/snapshot", current);
  ASSERT_TRUE(changed);
  EXPECT_EQ(changed->status, 200);
  EXPECT_NE(changed->get_header_value("ETag"), etag);
}

// Replicas all ask for the snapshot after a change, and a publication takes seconds: each request
// held a worker thread meanwhile, and six of them stalled the primary's /readyz for 6 s. At most
// two are answered at once; the rest get 503 with Retry-After and leave their threads free.
TEST_F(ReplicaSetTest, SnapshotDownloadsLeaveThePrimarysWorkersFree) {
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  addPincode(primary, "999125");
  std::vector<std::thread> downloads;
  std::vector<int> statuses(6, 0);
  std::vector<std::string> retry_after(6);
  std::vector<std::string> problem_type(6);
  for (std::size_t i = 0; i < statuses.size(); ++i) {
    downloads.emplace_back([&, i] {
      httplib::Client client("127.0.0.1", primary_->port());
      client.set_read_timeout(60, 0);
      const auto r = client.Get("/api/v1/registry/snapshot", Auth(replica_token_));
      statuses[i] = StatusOf(r);
      if (r) retry_after[i] = r->get_header_value("Retry-After");
      if (r && r->status == 503) problem_type[i] = json::parse(r->body).value("type", "");
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  httplib::Client probe("127.0.0.1", primary_->port());
  probe.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(probe.Get("/readyz")), 200);
  for (std::thread& t : downloads) t.join();
  int busy = 0;
  for (std::size_t i = 0; i < statuses.size(); ++i) {
    EXPECT_TRUE(statuses[i] == 200 || statuses[i] == 503) << statuses[i];
    if (statuses[i] == 503) {
      ++busy;
      EXPECT_EQ(retry_after[i], "1");
      // What a follower takes for "ask at the next poll" (any other 503 is a failure).
      EXPECT_EQ(problem_type[i], "tag:pintag,2026:snapshot-readers-busy");
    }
  }
  EXPECT_GE(busy, 1);
  EXPECT_LE(busy, 4);
}

// Only the primary's own "too many snapshots at once" 503 is "ask at the next poll", neither an
// answer nor a failure. A follower took every 503 with Retry-After for it, so a primary whose
// database stayed busy (503 Database Busy, Retry-After: 1), or a proxy in front of it answering
// "in maintenance, come back later", left its replicas reporting nothing wrong while they served
// an ever older snapshot. The proxy here is cpp-httplib's server answering as such a proxy does.
TEST_F(ReplicaSetTest, AFollowerCountsOtherUnavailableAnswersAsFailures) {
  httplib::Server proxy;
  proxy.Get("/api/v1/registry/snapshot", [](const httplib::Request&, httplib::Response& answer) {
    answer.status = 503;
    answer.set_header("Retry-After", "120");
    answer.set_content("<html><body>Down for maintenance</body></html>", "text/html");
  });
  const int port = proxy.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  std::thread serving([&] { proxy.listen_after_bind(); });  // bound: connections queue till then
  replica::SnapshotFollower follower({.primary_url = "http://127.0.0.1:" + std::to_string(port),
                                      .token = replica_token_,
                                      .path = dir_.file("followed.db")},
                                     [](const db::SnapshotInfo&) {});
  const auto answered = follower.fetch(std::nullopt);
  proxy.stop();
  serving.join();
  ASSERT_FALSE(answered) << "a primary that cannot send was taken for a current one";
  EXPECT_FALSE(follower.deferred());
  EXPECT_NE(answered.error().message.find("answered 503"), std::string::npos)
      << answered.error().message;

  // The primary itself: a snapshot, and nothing deferred.
  replica::SnapshotFollower direct(
      {.primary_url = primaryUrl(), .token = replica_token_, .path = dir_.file("direct.db")},
      [](const db::SnapshotInfo&) {});
  const auto fetched = direct.fetch(std::nullopt);
  ASSERT_TRUE(fetched) << fetched.error().message;
  EXPECT_TRUE(fetched->has_value());
  EXPECT_FALSE(direct.deferred());
}

TEST_F(ReplicaSetTest, ANewerSnapshotRenamedIntoPlaceIsServedWithoutDroppingRequestsInFlight) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  const Photo photo = PhotographLabel(primary, Auth(counter_token_), "110001", 20);
  ASSERT_FALSE(photo.jpeg.empty());

  constexpr int kClients = 4;
  std::atomic<bool> stop{false};
  std::atomic<int> failed{0}, went_back{0};
  std::array<std::atomic<int>, kClients> answered{};
  std::vector<std::thread> clients;
  clients.reserve(kClients);
  for (int t = 0; t < kClients; ++t) {
    clients.emplace_back([&, t] {
      httplib::Client client("127.0.0.1", replica.port());
      client.set_read_timeout(30, 0);
      std::int64_t last_version = 0;
      while (!stop) {
        httplib::Result r =
            t == 0 ? client.Post("/api/v1/detect", Auth(scanner_token_), photo.jpeg, "image/jpeg")
                   : client.Get("/api/v1/registry");
        if (!r || r->status != 200) {
          ++failed;
          continue;
        }
        ++answered[static_cast<std::size_t>(t)];
        const json body = Body(r);
        if (t == 0) {
          if (body["tags"].size() != 1 || body["tags"][0]["pincode"] != "110001") ++failed;
        } else {
          const std::int64_t version = body.value("registry_version", std::int64_t{0});
          if (version < last_version) ++went_back;
          last_version = version;
        }
      }
    });
  }
  // Every client answered at least `more` requests after `since` (their counts then), or the
  // minute ran out. Waiting on the counts, not on time, keeps the clients' requests on both
  // sides of the swaps however fast the machine is.
  const auto counts = [&] {
    std::array<int, kClients> now{};
    for (std::size_t t = 0; t < now.size(); ++t) now[t] = answered[t].load();
    return now;
  };
  const auto each_answered = [&](const std::array<int, kClients>& since, int more) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      const std::array<int, kClients> now = counts();
      bool all = true;
      for (std::size_t t = 0; t < now.size(); ++t) all = all && now[t] >= since[t] + more;
      if (all) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  };
  const bool running_before = each_answered({}, 2);
  // Five newer registries, each published by rename while the clients keep asking. The clients
  // are stopped and joined before any assertion can end the test.
  std::int64_t published_version = 0;
  std::int64_t served_version = 0;
  for (int i = 0; i < 5 && served_version == published_version; ++i) {
    addPincode(primary, std::to_string(999200 + i));
    publishTo("served.db");
    published_version = RegistryVersionAt(primary_->port());
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while ((served_version = RegistryVersionAt(replica.port())) != published_version &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  const bool running_after = each_answered(counts(), 2);
  stop = true;
  for (std::thread& c : clients) c.join();
  ASSERT_EQ(served_version, published_version);
  EXPECT_TRUE(running_before) << "a client got no answers before the first swap";
  EXPECT_TRUE(running_after) << "a client got no answers after the last swap";
  EXPECT_EQ(failed.load(), 0);
  EXPECT_EQ(went_back.load(), 0);
  httplib::Client client("127.0.0.1", replica.port());
  client.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(client.Get("/api/v1/pincodes/999204")), 200);
  EXPECT_EQ(StatusOf(client.Get("/readyz")), 200);

  // SIGHUP asks for a look now; the process goes on serving and then stops cleanly on SIGTERM.
  // Had SIGHUP kept its default action, it would have ended the process (exit 128 + 1, or gone
  // before the lookup), however the two signals' delivery interleaves. It says it looked (a
  // SIGHUP that found nothing new wrote nothing, so an operator could not tell it arrived).
  replica.signal(SIGHUP);
  EXPECT_EQ(RegistryVersionAt(replica.port()), published_version);
  EXPECT_TRUE(WaitUntil([&] {
    return stderrOf("replica-0")
               .find("SIGHUP: no new snapshot taken from " + snapshot +
                     " (serving registry version " + std::to_string(published_version) + ")") !=
           std::string::npos;
  })) << stderrOf("replica-0");
  EXPECT_EQ(replica.stop(SIGTERM, 30), 0);
}

TEST_F(ReplicaSetTest, AFileThatIsNotASnapshotIsIgnoredAndTheOldOneServed) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  const std::int64_t version = RegistryVersionAt(replica.port());
  ASSERT_GT(version, 0);
  const std::string junk = WriteFile(dir_.file("junk.db"), std::string(1 << 16, 'x'));
  std::filesystem::rename(junk, snapshot);
  replica.signal(SIGHUP);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (stderrOf("replica-0").find("ignoring the new file") == std::string::npos &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_NE(stderrOf("replica-0").find("ignoring the new file"), std::string::npos);
  // Many connections at once, so the pool opens new ones after the junk arrived.
  EXPECT_EQ(LookupsFromManyClients(replica.port()), 40);
  EXPECT_EQ(RegistryVersionAt(replica.port()), version);
  httplib::Client client("127.0.0.1", replica.port());
  client.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(client.Get("/readyz")), 200);

  // The refusal outlasts the replica: the junk is kept aside and the file is the registry served
  // again, for a restart or another replica to serve.
  EXPECT_EQ(ReadFile(snapshot + ".refused"), std::string(1 << 16, 'x'));
  ASSERT_TRUE(db::VerifySnapshot(snapshot).ok());
  EXPECT_EQ(db::VerifySnapshot(snapshot)->registry_version, version);

  // A replica started on the junk refuses to, says why, and leaves no files of its own beside it.
  const std::string junk_again = snapshot + ".refused";
  const std::set<std::string> before = ServingFiles(junk_again);
  const CommandResult refused =
      RunPintag("serve --read-only --port 0 --bind 127.0.0.1 --db " + junk_again + " --scan-log " +
                dir_.file("refused-scans.db"));
  EXPECT_NE(refused.status, 0);
  EXPECT_NE(refused.out.find("cannot serve " + junk_again + ":"), std::string::npos) << refused.out;
  // Named by its path, not by the replica's own link to it (".serving-…").
  EXPECT_EQ(refused.out.find(".serving-"), std::string::npos) << refused.out;
  EXPECT_EQ(ServingFiles(junk_again), before);
}

// The served file is a hard link to FILE, so a copy written over FILE in place (cp onto it)
// changes the registry being served. The replica turned unready, as it should, but then refused
// every good snapshot renamed into place ("cannot compare the keys" with the damaged one) and put
// the damaged file back: unready for good, its log saying it still served the old version.
TEST_F(ReplicaSetTest, AReplicaWhoseServedFileWasWrittenOverInPlaceTakesTheNextGoodOne) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  httplib::Client client = LoopbackClient(replica.port());
  ASSERT_EQ(StatusOf(client.Get("/readyz")), 200);
  {
    std::ofstream in_place(snapshot, std::ios::binary | std::ios::in | std::ios::out);
    in_place << std::string(1 << 16, 'x');  // the same inode, its first pages overwritten
  }
  EXPECT_EQ(WaitForStatus(client, "/readyz", 503), 503);
  ASSERT_TRUE(WaitUntil([&] {
    return stderrOf("replica-0").find("was written over in place") != std::string::npos;
  })) << stderrOf("replica-0");
  EXPECT_EQ(stderrOf("replica-0").find("still serving"), std::string::npos)
      << stderrOf("replica-0");

  httplib::Client primary = LoopbackClient(primary_->port());
  addPincode(primary, "999331");
  const std::string good = publishTo("good.db");
  std::filesystem::rename(good, snapshot);
  replica.signal(SIGHUP);
  EXPECT_EQ(WaitForStatus(client, "/readyz", 200), 200) << stderrOf("replica-0");
  EXPECT_EQ(WaitForStatus(client, "/api/v1/pincodes/999331", 200), 200);
  EXPECT_NE(stderrOf("replica-0").find("taking the new file at"), std::string::npos)
      << stderrOf("replica-0");
  EXPECT_FALSE(std::filesystem::exists(snapshot + ".refused"));
}

// Damage past the pages /readyz's query reads (the offices, here) left it answering 200 while
// searches answered 500: the replica's log said "Not ready", its load balancer kept sending.
TEST_F(ReplicaSetTest, AReplicaWhoseServedFileIsDamagedPastItsFirstPagesIsNotReady) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  httplib::Client client = LoopbackClient(replica.port());
  ASSERT_EQ(StatusOf(client.Get("/readyz")), 200);
  const auto size = std::filesystem::file_size(snapshot);
  ASSERT_GT(size, 8U << 20) << "a seeded registry";
  {
    std::fstream in_place(snapshot, std::ios::binary | std::ios::in | std::ios::out);
    in_place.seekp(static_cast<std::streamoff>(size / 10));
    in_place << std::string(800 << 10, '\0');  // 200 pages a tenth of the way in
  }
  ASSERT_TRUE(WaitUntil([&] {
    return stderrOf("replica-0").find("was written over in place") != std::string::npos;
  })) << stderrOf("replica-0");
  const auto ready = client.Get("/readyz");
  ASSERT_TRUE(ready);
  EXPECT_EQ(ready->status, 503) << ready->body;
  EXPECT_NE(ready->body.find("written over in place"), std::string::npos) << ready->body;
}

// The same for a --follow replica, with no change at the primary: the follower still named the
// version it had installed, the primary answered 304, and the replica stayed unready until the
// registry next changed.
TEST_F(ReplicaSetTest, AFollowerWhoseServedFileWasWrittenOverInPlaceFetchesItAgain) {
  ServerProcess& replica = startFollower(0);
  ASSERT_TRUE(replica.ok());
  httplib::Client client = LoopbackClient(replica.port());
  ASSERT_EQ(StatusOf(client.Get("/readyz")), 200);
  {
    std::ofstream in_place(replicaDb(0), std::ios::binary | std::ios::in | std::ios::out);
    in_place << std::string(1 << 16, 'x');
  }
  ASSERT_TRUE(WaitUntil([&] {
    return stderrOf("replica-0").find("was written over in place") != std::string::npos;
  })) << stderrOf("replica-0");
  EXPECT_EQ(WaitForStatus(client, "/readyz", 200), 200) << stderrOf("replica-0");
  EXPECT_EQ(WaitForStatus(client, "/api/v1/pincodes/110001", 200), 200);
  EXPECT_EQ(RegistryVersionAt(replica.port()), RegistryVersionAt(primary_->port()));
}

// A follower's FILE removed (a cleanup, a mistaken rm) was not written again until the registry
// next changed: the replica served on from its link, and a restart in that window found nothing
// and had to wait for the primary.
TEST_F(ReplicaSetTest, AFollowerWhoseFileWasRemovedFetchesItAgain) {
  ServerProcess& replica = startFollower(0);
  ASSERT_TRUE(replica.ok());
  const std::int64_t version = RegistryVersionAt(replica.port());
  ASSERT_TRUE(std::filesystem::remove(replicaDb(0)));
  ASSERT_TRUE(WaitUntil([&] { return std::filesystem::exists(replicaDb(0)); }))
      << stderrOf("replica-0");
  const CommandResult verified = RunPintag("snapshot --verify " + replicaDb(0));
  EXPECT_EQ(verified.status, 0) << verified.out;
  EXPECT_NE(verified.out.find("registry version " + std::to_string(version)), std::string::npos)
      << verified.out;
  httplib::Client client = LoopbackClient(replica.port());
  EXPECT_EQ(StatusOf(client.Get("/readyz")), 200);
  EXPECT_EQ(StatusOf(client.Get("/api/v1/pincodes/110001")), 200);
}

// The manual way to update a --read-only replica is `pintag snapshot` and a rename. A file from
// a registry that gave a served key to another pincode (an older backup run as a primary) was
// taken: every label printed with that key then read as the other pincode.
TEST_F(ReplicaSetTest, AReadOnlyReplicaRefusesAFileThatGivesAServedKeyToAnotherPincode) {
  const std::string older = publishTo("older.db");
  httplib::Client primary = LoopbackClient(primary_->port());
  addPincode(primary, "999301");
  const std::string snapshot = publishTo("served.db");
  ServerProcess& replica = startReadOnly(0, snapshot);
  ASSERT_TRUE(replica.ok());
  httplib::Client client = LoopbackClient(replica.port());
  const json served = Body(client.Get("/api/v1/pincodes/999301"));
  ASSERT_TRUE(served.contains("key")) << served.dump();
  const std::string key = std::to_string(served["key"].get<std::int64_t>());
  const std::int64_t version = RegistryVersionAt(replica.port());

  // The fork: the older registry, given another pincode that takes the same key (999301's key is
  // free there, so a pincode whose probe starts at it gets it).
  const std::string fork_db = dir_.file("fork.db");
  std::filesystem::copy_file(older, fork_db);
  std::string given_to;
  {
    db::Connection fork(fork_db, {.create = false});
    int other = 0;
    for (int pin = 999999; pin >= 100000 && other == 0; --pin) {
      if (pin != 999301 && StartSlot(Pincode(pin)).value() == served["key"].get<int>() &&
          !db::LookupPincode(fork, Pincode(pin)).ok()) {
        other = pin;
      }
    }
    ASSERT_NE(other, 0);
    ASSERT_TRUE(db::AddPincode(fork, Pincode(other), {TestOffice("Fork Nagar")}).ok());
    ASSERT_EQ(db::LookupPincode(fork, Pincode(other))->key.value(), served["key"].get<int>());
    ASSERT_TRUE(db::WriteSnapshot(fork, dir_.file("fork-snapshot.db")).ok());
    given_to = std::to_string(other);
  }
  std::filesystem::rename(dir_.file("fork-snapshot.db"), snapshot);
  replica.signal(SIGHUP);
  ASSERT_TRUE(WaitUntil([&] {
    return stderrOf("replica-0").find("ignoring the new file") != std::string::npos;
  })) << stderrOf("replica-0");
  const std::string log = stderrOf("replica-0");
  EXPECT_NE(log.find("key " + key + " (pincode 999301) is given to " + given_to), std::string::npos)
      << log;
  EXPECT_NE(log.find("misrouted"), std::string::npos) << log;
  EXPECT_EQ(Body(client.Get("/api/v1/keys/" + key)).value("pincode", ""), "999301");
  EXPECT_EQ(RegistryVersionAt(replica.port()), version);
  EXPECT_EQ(StatusOf(client.Get("/readyz")), 200);
  // The refusal outlasts this replica: the fork is kept aside, and a replica started on the file
  // now (a restart, another host sharing it) serves the registry served before, not the fork.
  EXPECT_NE(log.find("kept as " + snapshot + ".refused"), std::string::npos) << log;
  ASSERT_TRUE(db::VerifySnapshot(snapshot + ".refused").ok());
  ServerProcess& second = startReadOnly(1, snapshot);
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(RegistryVersionAt(second.port()), version);
  httplib::Client second_client = LoopbackClient(second.port());
  EXPECT_EQ(Body(second_client.Get("/api/v1/keys/" + key)).value("pincode", ""), "999301");

  // A newer snapshot of the primary, which keeps every key, is still taken.
  addPincode(primary, "999303");
  const std::string newer = publishTo("newer.db");
  std::filesystem::rename(newer, snapshot);
  replica.signal(SIGHUP);
  EXPECT_EQ(WaitForStatus(client, "/api/v1/pincodes/999303", 200), 200) << stderrOf("replica-0");
}

/// How often `text` holds `part`.
std::size_t Occurrences(const std::string& text, const std::string& part) {
  std::size_t count = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) {
    ++count;
  }
  return count;
}

/// How many whole snapshots the primary has sent so far (its access log's 200s on the route).
std::size_t SnapshotsSent(const std::string& log) {
  return Occurrences(log, "path=/api/v1/registry/snapshot status=200");
}

// A follower starting without a snapshot downloaded it twice: once to start on, and again at
// its first poll, since the follower that polls did not know the ETag of the one that fetched.
// Its polls answered 304, one a second in production, each wrote an access line on the primary
// (86,400 a day for each replica): now the first, then one a minute saying how many were left
// out (RoutineAccessThrottle); the metrics still count every one.
TEST_F(ReplicaSetTest,
       AFollowerStartingWithoutASnapshotDownloadsItOnceAndItsPollsAreNotLoggedEach) {
  const std::size_t before = SnapshotsSent(stderrOf("primary"));
  ServerProcess& replica = startFollower(0);
  ASSERT_TRUE(replica.ok());
  httplib::Client primary = LoopbackClient(primary_->port());
  // Polls every 200 ms: a few of them, each a 304.
  ASSERT_TRUE(WaitUntil([&] { return MetricAt(primary, SnapshotAnswers(304)) >= 3; }));
  EXPECT_EQ(SnapshotsSent(stderrOf("primary")) - before, 1U) << stderrOf("primary");
  const std::string log = stderrOf("primary");
  EXPECT_EQ(Occurrences(log, "path=/api/v1/registry/snapshot status=304"), 1U) << log;
  EXPECT_EQ(Occurrences(log, "left_out="), 0U) << log;
}

// A snapshot downloaded whole and then not installed (a full disk, say; here the replica's path
// is a directory, which the rename cannot replace) was downloaded again at every poll, 35 MB
// every 200 ms, each holding one of the primary's two snapshot slots. It now waits 1 s, 2 s, …
TEST_F(ReplicaSetTest, AFollowerThatCannotInstallBacksOffItsDownloads) {
  const std::string blocked = dir_.file("blocked-replica.db");
  std::filesystem::create_directory(blocked);
  replica::SnapshotFollower follower(
      {.primary_url = primaryUrl(), .token = replica_token_, .path = blocked},
      [](const db::SnapshotInfo&) {});
  const std::size_t before = SnapshotsSent(stderrOf("primary"));
  const auto sent = [&](std::size_t count) {  // the access log is written as the answer ends
    return WaitUntil([&] { return SnapshotsSent(stderrOf("primary")) - before >= count; },
                     std::chrono::seconds(10));
  };
  const auto first = follower.fetch(std::nullopt);
  const auto failed_at = std::chrono::steady_clock::now();
  // Asked again at once (well within the 1 s): the same error, and nothing downloaded.
  const auto again = follower.fetch(std::nullopt);
  ASSERT_FALSE(first);
  EXPECT_NE(first.error().message.find("downloaded again after 1 s, 2 s"), std::string::npos)
      << first.error().message;
  EXPECT_EQ(first.error().message.find(".tmp-"), std::string::npos) << first.error().message;
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error().message, first.error().message);
  ASSERT_TRUE(sent(1));
  // After the delay it downloads once more, and at once after that it does not (2 s now).
  std::this_thread::sleep_until(failed_at + std::chrono::milliseconds(1100));
  const auto later = follower.fetch(std::nullopt);
  const auto failed_again_at = std::chrono::steady_clock::now();
  EXPECT_FALSE(follower.fetch(std::nullopt));
  ASSERT_FALSE(later);
  EXPECT_EQ(later.error().message, first.error().message);
  ASSERT_TRUE(sent(2));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(SnapshotsSent(stderrOf("primary")) - before, 2U);
  // Room again: the next download after the delay is installed.
  std::filesystem::remove(blocked);
  std::this_thread::sleep_until(failed_again_at + std::chrono::milliseconds(2100));
  const auto installed = follower.fetch(std::nullopt);
  ASSERT_TRUE(installed) << installed.error().message;
  EXPECT_TRUE(installed->has_value());
}

// A primary whose first snapshot could not be written (a full disk under --snapshot) exited,
// the only writer down over its replicas' disk, although later failures are retried. It now
// starts, says so, answers replicas 503 and publishes once it can. A --snapshot directory that
// does not exist is still refused at start: that is a mistake in the command.
TEST_F(ReplicaSetTest, APrimaryStartsWhenItsFirstSnapshotCannotBeWrittenAndPublishesLater) {
  primary_.reset();
  const std::string blocked = dir_.file("blocked.db");
  std::filesystem::create_directory(blocked);  // a rename onto it fails, as a full disk's write
  primary_ = std::make_unique<ServerProcess>(
      std::vector<std::string>{"--db", primary_db_, "--threads", "4", "--snapshot", blocked},
      dir_.file("primary-blocked.err"));
  ASSERT_TRUE(primary_->ok()) << ReadFile(dir_.file("primary-blocked.err"));
  const std::string log = ReadFile(dir_.file("primary-blocked.err"));
  EXPECT_NE(log.find("cannot publish a snapshot to " + blocked), std::string::npos) << log;
  EXPECT_NE(log.find("starting without a published snapshot"), std::string::npos) << log;
  httplib::Client primary = LoopbackClient(primary_->port());
  const auto refused = primary.Get("/api/v1/registry/snapshot", Auth(replica_token_));
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 503) << refused->body;
  const json status = Body(primary.Get("/api/v1/registry"));
  EXPECT_TRUE(status["snapshot"]["failing_since"].is_string()) << status.dump();
  // Writes go on meanwhile, and once the path is free the snapshot holds them.
  addPincode(primary, "999321");
  std::filesystem::remove(blocked);
  EXPECT_TRUE(WaitUntil([&] {
    const auto r = primary.Get("/api/v1/registry/snapshot", Auth(replica_token_));
    return r && r->status == 200;
  }));
  const json published = Body(primary.Get("/api/v1/registry"));
  EXPECT_EQ(published["snapshot"]["published_version"], published["registry_version"])
      << published.dump();

  const CommandResult missing = RunPintag("serve --port 0 --db " + primary_db_ + " --snapshot " +
                                          dir_.file("no-such-dir/snap.db"));
  EXPECT_EQ(missing.status, 2) << missing.out;
  EXPECT_NE(missing.out.find("does not exist"), std::string::npos) << missing.out;
}

// The primary trusted the version it remembered: a published file removed or overwritten by
// another process was served as it was (5 bytes of junk with the live ETag) or answered 503 until
// the next write. And a publication that failed was tried again, whole, every half second.
TEST_F(ReplicaSetTest, ThePrimaryRepublishesASnapshotOthersChangedAndBacksOffWhileItCannot) {
  const std::string published = dir_.file("published.db");
  httplib::Client primary = LoopbackClient(primary_->port());
  const auto snapshot = [&] {
    return primary.Get("/api/v1/registry/snapshot", Auth(replica_token_));
  };
  const auto is_whole_snapshot = [](const httplib::Result& r) {
    return r && r->status == 200 && r->body.size() > 1'000'000 &&
           r->body.rfind("SQLite format 3", 0) == 0;
  };
  ASSERT_TRUE(is_whole_snapshot(snapshot()));
  const json status = Body(primary.Get("/api/v1/registry"));
  EXPECT_EQ(status["snapshot"]["published_version"], status["registry_version"]) << status.dump();
  EXPECT_TRUE(status["snapshot"]["error"].is_null()) << status.dump();

  std::filesystem::remove(published);
  EXPECT_TRUE(is_whole_snapshot(snapshot()));
  WriteFile(published, "junk\n");
  EXPECT_TRUE(is_whole_snapshot(snapshot()));
  EXPECT_NE(stderrOf("primary").find("was removed or changed by another process"),
            std::string::npos);

  // The path taken by a directory: each write makes a publication fail. They are tried at most
  // once a retry delay (1 s, then 2 s, …), each logged, and the primary says so.
  std::filesystem::remove(published);
  std::filesystem::create_directory(published);
  const auto failures_logged = [&] {
    const std::string log = stderrOf("primary");
    std::size_t count = 0;
    for (std::size_t at = log.find("cannot publish a snapshot"); at != std::string::npos;
         at = log.find("cannot publish a snapshot", at + 1)) {
      ++count;
    }
    return count;
  };
  const auto started = std::chrono::steady_clock::now();
  addPincode(primary, "999311");
  ASSERT_TRUE(WaitUntil([&] { return failures_logged() >= 1; }));
  for (int i = 0; i < 10; ++i) {
    const auto r = snapshot();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 503) << r->body;
    EXPECT_NE(r->body.find("is a directory, not a file"), std::string::npos) << r->body;
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  // Each refused poll has its access line, not an error line too (the publisher's tries are
  // logged, with their backoff).
  EXPECT_EQ(stderrOf("primary").find("/api/v1/registry/snapshot: 503"), std::string::npos)
      << stderrOf("primary");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  // Without the delay, 2 tries a second from the thread and one per request: over 15 here.
  EXPECT_LE(failures_logged(), static_cast<std::size_t>(std::log2(seconds + 1)) + 2)
      << seconds << " s:\n"
      << stderrOf("primary");
  const json failing = Body(primary.Get("/api/v1/registry"));
  // The same words at every try (the count is in the log line), so that replicas quoting it
  // log it once.
  EXPECT_NE(failing["snapshot"]["error"].get<std::string>().find("is a directory, not a file"),
            std::string::npos)
      << failing.dump();
  EXPECT_EQ(failing["snapshot"]["error"].get<std::string>().find("in a row"), std::string::npos)
      << failing.dump();
  EXPECT_TRUE(failing["snapshot"]["failing_since"].is_string()) << failing.dump();
  EXPECT_TRUE(failing["snapshot"]["published_version"].is_null()) << failing.dump();
  const auto metrics = [&] {
    const auto r = primary.Get("/metrics");
    return r ? r->body : std::string();
  };
  EXPECT_NE(metrics().find("\npintag_snapshot_publish_failing 1\n"), std::string::npos);

  // The path free again: the next try publishes, and the status clears.
  std::filesystem::remove(published);
  EXPECT_TRUE(WaitUntil([&] { return is_whole_snapshot(snapshot()); })) << stderrOf("primary");
  const json recovered = Body(primary.Get("/api/v1/registry"));
  EXPECT_EQ(recovered["snapshot"]["published_version"], recovered["registry_version"])
      << recovered.dump();
  EXPECT_TRUE(recovered["snapshot"]["error"].is_null()) << recovered.dump();
  EXPECT_NE(metrics().find("\npintag_snapshot_publish_failing 0\n"), std::string::npos);
}

// Both commands default to --db pintag.db: a follower started in its primary's directory was
// handed the primary's live file, renamed a snapshot over it, and the primary's write-ahead log
// then corrupted the new file. A replica refuses any registry a server writes, before it fetches.
TEST_F(ReplicaSetTest, AReplicaNeverReplacesALiveRegistry) {
  const auto inode = [](const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 ? st.st_ino : ino_t{0};
  };
  const ino_t before = inode(primary_db_);
  const std::string token_file = dir_.file("replica.token");
  for (const std::string& mode : {"--follow " + primaryUrl() + " --follow-token-file " + token_file,
                                  std::string("--read-only")}) {
    const CommandResult refused =
        RunPintag("serve --port 0 --bind 127.0.0.1 --db " + primary_db_ + " " + mode +
                  " --scan-log " + dir_.file("refused-scans.db"));
    EXPECT_EQ(refused.status, 1) << mode << ": " << refused.out;
    EXPECT_NE(refused.out.find(primary_db_ + " is a live database"), std::string::npos)
        << refused.out;
  }
  EXPECT_EQ(inode(primary_db_), before);
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  EXPECT_EQ(StatusOf(primary.Get("/readyz")), 200);
  addPincode(primary, "999124");

  // Stopped, the primary's file has no log beside it, and is still a registry a server writes.
  ASSERT_EQ(primary_->stop(SIGTERM, 30), 0);
  ASSERT_FALSE(std::filesystem::exists(primary_db_ + "-wal"));
  const CommandResult refused =
      RunPintag("serve --port 0 --bind 127.0.0.1 --read-only --db " + primary_db_ + " --scan-log " +
                dir_.file("refused-scans.db"));
  EXPECT_EQ(refused.status, 1) << refused.out;
  EXPECT_NE(refused.out.find("in WAL mode"), std::string::npos) << refused.out;
  EXPECT_EQ(inode(primary_db_), before);
  EXPECT_EQ(CountRows(primary_db_, "pincodes WHERE pincode = 999124"), 1);
}

// A --scan-log naming a registry snapshot (the replica's own --db, another replica's file) was
// switched to WAL and given a scan_log table: the snapshot was then refused by every install and
// could not be served again.
TEST_F(ReplicaSetTest, AScanLogNamingARegistrySnapshotIsRefusedAndTheSnapshotLeftAsItWas) {
  const std::string mine = dir_.file("mine.db");
  const std::string theirs = dir_.file("theirs.db");
  for (const std::string& file : {mine, theirs}) {
    const CommandResult made = RunPintag("snapshot --db " + primary_db_ + " --out " + file);
    ASSERT_EQ(made.status, 0) << made.out;
  }
  const std::string bytes_before = ReadFile(theirs);
  for (const std::string& scan_log : {mine, theirs}) {
    // Under a timeout: a replica that took the file would serve on and never exit.
    std::string serve = "timeout 30 " + PintagExe();
    serve += " serve --port 0 --bind 127.0.0.1 --read-only --db " + mine;
    serve += " --scan-log " + scan_log + " 2>&1";
    const CommandResult refused = RunShell(serve);
    // Its own --db is a usage error; another file is looked at, and refused for its tables.
    const bool own = scan_log == mine;
    EXPECT_EQ(refused.status, own ? 2 : 1) << refused.out;
    EXPECT_NE(refused.out.find(own ? "--scan-log " + mine + " is the replica's --db"
                                   : "scan log " + scan_log + ": the file holds other tables"),
              std::string::npos)
        << refused.out;
    const CommandResult verified = RunPintag("snapshot --verify " + scan_log);
    EXPECT_EQ(verified.status, 0) << verified.out;
  }
  // A follower says so at once, not once its primary (here none) has sent a first snapshot.
  const CommandResult follower =
      RunShell("PINTAG_FOLLOW_TOKEN=pt_1_" + std::string(43, 'A') + " timeout 30 " + PintagExe() +
               " serve --port 0 --bind 127.0.0.1 --follow http://127.0.0.1:9 --db " +
               dir_.file("new.db") + " --scan-log " + theirs + " 2>&1");
  EXPECT_EQ(follower.status, 1) << follower.out;
  EXPECT_NE(follower.out.find("the file holds other tables"), std::string::npos) << follower.out;
  EXPECT_EQ(ReadFile(theirs), bytes_before);
  EXPECT_FALSE(std::filesystem::exists(theirs + "-wal"));
  // A scan log of its own beside them is made, and the replica serves.
  ServerProcess replica({"--db", mine, "--read-only", "--scan-log", dir_.file("mine-scans.db")},
                        dir_.file("mine.log"));
  ASSERT_TRUE(replica.ok());
}

// The URL the primary's banner prints ends in a slash; a follower given it fetched from "//api/…"
// and waited forever. A URL with a path is refused at start, not retried.
TEST_F(ReplicaSetTest, FollowTakesThePrimaryUrlAsTheBannerPrintsIt) {
  ServerProcess follower(
      {"--db", replicaDb(0), "--follow", primaryUrl() + "/", "--follow-token-file",
       dir_.file("replica.token"), "--scan-log", replicaScanLog(0)},
      dir_.file("replica-0.err"), 60);
  ASSERT_TRUE(follower.ok()) << stderrOf("replica-0");
  EXPECT_EQ(RegistryVersionAt(follower.port()), RegistryVersionAt(primary_->port()));
  httplib::Client client("127.0.0.1", follower.port());
  client.set_read_timeout(30, 0);
  EXPECT_EQ(Body(client.Get("/api/v1/registry"))["primary"], primaryUrl());

  for (const std::string& url :
       {primaryUrl() + "/pintag", std::string("127.0.0.1:8090"), std::string("ftp://host"),
        std::string("http://127.0.0.1:99999999999"), std::string("http://127.0.0.1:0"),
        std::string("http://:8090"), std::string("http://host:abc")}) {
    const CommandResult refused =
        RunPintag("serve --port 0 --db " + replicaDb(1) + " --follow " + url +
                  " --follow-token-file " + dir_.file("replica.token"));
    EXPECT_EQ(refused.status, 2) << url << ": " << refused.out;
    EXPECT_NE(refused.out.find("--follow takes the primary's base URL"), std::string::npos)
        << refused.out;
  }
}

// A replica not told its primary says so: null in /api/v1/registry, as the API promises, and a
// refused write says how to name it.
TEST_F(ReplicaSetTest, AReplicaNotToldItsPrimaryNamesNone) {
  const std::string snapshot = publishTo("served.db");
  ServerProcess replica({"--db", snapshot, "--read-only", "--scan-log", replicaScanLog(0)},
                        dir_.file("replica-0.err"), 60);
  ASSERT_TRUE(replica.ok()) << stderrOf("replica-0");
  httplib::Client client("127.0.0.1", replica.port());
  client.set_read_timeout(30, 0);
  const json status = Body(client.Get("/api/v1/registry"));
  EXPECT_EQ(status["role"], "replica");
  EXPECT_TRUE(status["primary"].is_null()) << status.dump();
  const auto refused =
      client.Post("/api/v1/pincodes", Auth(admin_token_), "{}", "application/json");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403);
  EXPECT_NE(refused->body.find("start it with --primary URL"), std::string::npos) << refused->body;
}

// A registry version counts changes within one database's history. A primary restored from a
// backup counts again from the backup's version: after as many changes as the replicas saw since,
// it is at their version with other rows. They answered 304 to it, and served rows the primary
// no longer had, until its next change. The ETag names the primary's run too, so a follower takes
// a restored registry that keeps its keys. One that lost keys the follower serves would give them
// to the next pincodes it adds, and labels printed with them would be misrouted: the follower
// refuses it, says why, and follows again once the primary is restored from the follower's file.
TEST_F(ReplicaSetTest, AFollowerTakesARestoredRegistryOnlyWhenItKeepsTheKeysServed) {
  const auto restore_primary = [&](const std::string& from, const std::string& log_name,
                                   const std::function<void(db::Connection&)>& change) {
    const int port = primary_->port();
    ASSERT_EQ(primary_->stop(SIGTERM, 30), 0);
    std::filesystem::copy_file(from, primary_db_,
                               std::filesystem::copy_options::overwrite_existing);
    {
      db::Connection restored(primary_db_, {.create = false});
      restored.execute("PRAGMA journal_mode=WAL");
      change(restored);
    }
    primary_ = std::make_unique<ServerProcess>(
        std::vector<std::string>{"--db", primary_db_, "--threads", "4", "--snapshot",
                                 dir_.file("published.db")},
        dir_.file(log_name + ".err"), 60, port);
    ASSERT_TRUE(primary_->ok()) << stderrOf(log_name);
  };
  const auto add_directly = [](db::Connection& connection, int pin) {
    ASSERT_TRUE(db::AddPincode(connection, Pincode(pin), {TestOffice("Restored Nagar")}).ok())
        << pin;
  };
  const std::string before_999202 = publishTo("backup-old.db");
  ServerProcess& follower = startFollower(0);
  ASSERT_TRUE(follower.ok());
  httplib::Client replica = LoopbackClient(follower.port());
  httplib::Client primary = LoopbackClient(primary_->port());
  addPincode(primary, "999202");
  ASSERT_EQ(WaitForStatus(replica, "/api/v1/pincodes/999202", 200), 200) << stderrOf("replica-0");
  const std::string with_999202 = publishTo("backup-new.db");
  // Three changes, as many as adding a pincode with an office makes.
  for (const std::string pin : {"999202", "110001", "110002"}) {
    ASSERT_EQ(StatusOf(primary.Post("/api/v1/pincodes/" + pin + "/retire", Auth(admin_token_), "",
                                    "application/json")),
              200);
  }
  WaitUntil([&] {
    return Body(replica.Get("/api/v1/pincodes/110002")).value("status", "") == "retired";
  });
  const std::int64_t held = RegistryVersionAt(follower.port());

  // Restored from the newer backup, one pincode added: the replica's version, other rows, every
  // key kept. The follower takes it (999202 active again, 999203 there).
  restore_primary(with_999202, "primary-restored", [&](db::Connection& restored) {
    add_directly(restored, 999203);
    const auto version = db::RegistryVersion(restored);
    ASSERT_TRUE(version.ok());
    ASSERT_EQ(*version, held) << "the restored registry is not at the replica's version";
  });
  EXPECT_EQ(WaitForStatus(replica, "/api/v1/pincodes/999203", 200), 200) << stderrOf("replica-0");
  EXPECT_EQ(Body(replica.Get("/api/v1/pincodes/999202")).value("status", ""), "active");
  EXPECT_EQ(RegistryVersionAt(follower.port()), held);

  // Restored from the older backup, which lacks 999202: refused, named, the replica still ready.
  const std::int64_t key_of_999202 = Body(replica.Get("/api/v1/pincodes/999202"))["key"];
  restore_primary(before_999202, "primary-old",
                  [&](db::Connection& restored) { add_directly(restored, 999204); });
  const auto follow = [&] { return Body(replica.Get("/api/v1/registry"))["follow"]; };
  const auto follow_error = [&] {
    const json status = follow();
    return status["error"].is_string() ? status["error"].get<std::string>() : std::string();
  };
  WaitUntil([&] { return follow_error().find("keep the keys") != std::string::npos; });
  const std::string error = follow_error();
  EXPECT_NE(error.find("key " + std::to_string(key_of_999202) + " (pincode 999202)"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("misrouted"), std::string::npos) << error;
  EXPECT_EQ(StatusOf(replica.Get("/api/v1/pincodes/999202")), 200);
  EXPECT_EQ(StatusOf(replica.Get("/api/v1/pincodes/999204")), 404);
  EXPECT_EQ(StatusOf(replica.Get("/readyz")), 200);
  // Logged just after the status is set.
  WaitUntil([&] { return stderrOf("replica-0").find("keep the keys") != std::string::npos; });
  EXPECT_NE(stderrOf("replica-0").find("does not keep the keys"), std::string::npos);
  // Not downloaded again at every poll (200 ms) while the primary serves the same registry: the
  // follower names the refused ETag, gets 304s, and the refusal stands. Counted by the primary's
  // metrics: its log writes one 304 a minute.
  const double sent_before = MetricAt(primary, SnapshotAnswers(200));
  const double not_modified_before = std::max(MetricAt(primary, SnapshotAnswers(304)), 0.0);
  const json answered_before = follow()["last_answer"];
  std::this_thread::sleep_for(std::chrono::seconds(2));
  EXPECT_EQ(MetricAt(primary, SnapshotAnswers(200)), sent_before);
  EXPECT_GE(MetricAt(primary, SnapshotAnswers(304)) - not_modified_before, 3.0);
  EXPECT_NE(follow_error().find("keep the keys"), std::string::npos) << follow_error();
  // The primary answers every poll: its last answer moves on while the refusal stands (it stood
  // at the last answer before the restore, as if the primary were gone).
  ASSERT_TRUE(answered_before.is_string()) << answered_before.dump();
  EXPECT_GT(follow()["last_answer"].get<std::string>(), answered_before.get<std::string>());

  // The way back SCALING.md gives: the primary restored from the replica's own file.
  restore_primary(replicaDb(0), "primary-from-replica", [](db::Connection&) {});
  addPincode(primary, "999205");
  EXPECT_EQ(WaitForStatus(replica, "/api/v1/pincodes/999205", 200), 200) << stderrOf("replica-0");
  EXPECT_EQ(StatusOf(replica.Get("/api/v1/pincodes/999202")), 200);
  WaitUntil([&] { return follow()["error"].is_null(); });
  EXPECT_TRUE(follow()["error"].is_null()) << follow().dump();
}

// Something at a follower's primary URL that is not a working primary: it reads each request and
// then answers nothing (`hang`), or declares a 2 GiB body and sends zeros (`huge`).
class StubPrimary {
 public:
  explicit StubPrimary(bool huge) : huge_(huge) {
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof address;
    EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    EXPECT_EQ(::listen(listener_, 8), 0);
    EXPECT_EQ(::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &size), 0);
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  StubPrimary(const StubPrimary&) = delete;
  StubPrimary& operator=(const StubPrimary&) = delete;
  ~StubPrimary() {
    stopping_ = true;
    ::shutdown(listener_, SHUT_RDWR);
    thread_.join();
    ::close(listener_);
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  int requests() const { return requests_; }

 private:
  void serve() {
    std::vector<int> held;
    while (!stopping_) {
      const int fd = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) break;
      test::ReceiveUntil(
          fd, 2, [](const std::string& r) { return r.find("\r\n\r\n") != std::string::npos; });
      ++requests_;
      if (huge_) {
        test::SendAll(fd,
                      "HTTP/1.1 200 OK\r\nContent-Type: application/vnd.sqlite3\r\n"
                      "Content-Length: 2147483648\r\n\r\n" +
                          std::string(1 << 20, '\0'));
        ::close(fd);
      } else {
        held.push_back(fd);  // never answered
      }
    }
    for (const int fd : held) ::close(fd);
  }

  bool huge_;
  int listener_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<int> requests_{0};
  std::thread thread_;
};

// A follower that serves a snapshot and polls a primary that never answers stopped only after the
// read timeout (30 s: past Docker's and Kubernetes's grace), and one sent a body of 2 GiB held it
// all in memory. SIGTERM now cancels the download, and a body over the limit is refused as it
// arrives, the old snapshot served.
TEST_F(ReplicaSetTest, AFollowerStopsAtOnceAndRefusesAnOversizedSnapshot) {
  ServerProcess& first = startFollower(0);
  ASSERT_TRUE(first.ok());
  ASSERT_EQ(first.stop(SIGTERM, 30), 0);
  const std::int64_t version = RegistryVersionAt(primary_->port());

  for (const bool huge : {false, true}) {
    StubPrimary stub(huge);
    ServerProcess follower({"--db", replicaDb(0), "--follow", stub.url(), "--follow-token-file",
                            dir_.file("replica.token"), "--follow-interval-ms", "200", "--scan-log",
                            replicaScanLog(0)},
                           dir_.file("replica-0.err"), 60);
    ASSERT_TRUE(follower.ok()) << stderrOf("replica-0");
    // Two refusals of the huge body (the second after the 1 s backoff, logged as the first,
    // once), or the first poll.
    WaitUntil([&] { return stub.requests() >= (huge ? 2 : 1); });
    if (huge) {
      ASSERT_GE(stub.requests(), 2);
      // Refused at every poll, logged once.
      const std::string log = stderrOf("replica-0");
      const std::string refusal = "sent a snapshot of more than 1024 MiB";
      const std::size_t first_refusal = log.find(refusal);
      EXPECT_NE(first_refusal, std::string::npos) << log;
      EXPECT_EQ(log.find(refusal, first_refusal + 1), std::string::npos) << log;
      EXPECT_EQ(RegistryVersionAt(follower.port()), version);
    } else {
      ASSERT_EQ(stub.requests(), 1);  // its first poll hangs
    }
    const auto asked = std::chrono::steady_clock::now();
    EXPECT_EQ(follower.stop(SIGTERM, 60), 0) << "huge " << huge;
    EXPECT_LT(std::chrono::steady_clock::now() - asked, std::chrono::seconds(15))
        << "huge " << huge;
  }
}

// A follower whose token was revoked went on serving its last snapshot, ready, with nothing to
// show it had stopped following, and SIGHUP did not re-read its token file. Its registry status
// now says how its polls go, and SIGHUP takes a rotated token.
TEST_F(ReplicaSetTest, AFollowersStatusShowsItsPollsAndSigHupTakesARotatedToken) {
  ServerProcess& follower = startFollower(0);
  ASSERT_TRUE(follower.ok());
  httplib::Client replica = LoopbackClient(follower.port());
  httplib::Client primary = LoopbackClient(primary_->port());
  const auto follow = [&] { return Body(replica.Get("/api/v1/registry"))["follow"]; };
  const auto metrics = [&] {
    const httplib::Result got = replica.Get("/metrics");
    return got ? got->body : std::string();
  };
  WaitUntil([&] { return !follow()["last_answer"].is_null(); });
  EXPECT_TRUE(follow()["last_answer"].is_string()) << follow().dump();
  EXPECT_TRUE(follow()["error"].is_null()) << follow().dump();
  EXPECT_NE(metrics().find("\npintag_follow_failing 0\n"), std::string::npos) << metrics();
  EXPECT_NE(metrics().find("\npintag_follow_last_answer_timestamp_seconds "), std::string::npos);
  EXPECT_EQ(metrics().find("pintag_follow_failing_since_timestamp_seconds"), std::string::npos);

  // Revoked on the primary: the replica still serves and is ready, and its status says why it
  // no longer follows.
  std::int64_t replica_token_id = -1;
  const json tokens = Body(primary.Get("/api/v1/tokens", Auth(admin_token_)));
  for (const json& t : tokens["tokens"]) {
    if (t["role"] == "replica" && t["revoked_at"].is_null()) replica_token_id = t["id"];
  }
  ASSERT_GT(replica_token_id, 0);
  ASSERT_EQ(StatusOf(primary.Post("/api/v1/tokens/" + std::to_string(replica_token_id) + "/revoke",
                                  Auth(admin_token_), "", "application/json")),
            200);
  WaitUntil([&] { return !follow()["error"].is_null(); });
  EXPECT_NE(follow()["error"].get<std::string>().find("401"), std::string::npos) << follow().dump();
  EXPECT_TRUE(follow()["failing_since"].is_string());
  EXPECT_EQ(StatusOf(replica.Get("/readyz")), 200);
  EXPECT_NE(metrics().find("\npintag_follow_failing 1\n"), std::string::npos) << metrics();
  EXPECT_NE(metrics().find("\npintag_follow_failing_since_timestamp_seconds "), std::string::npos);

  // A new token in the file, SIGHUP: it follows again.
  const json made =
      Body(primary.Post("/api/v1/tokens", Auth(admin_token_),
                        R"({"role": "replica", "label": "rotated"})", "application/json"));
  ASSERT_TRUE(made["secret"].is_string()) << made.dump();
  WriteFile(dir_.file("replica.token"), made["secret"].get<std::string>() + "\n");
  follower.signal(SIGHUP);
  // Taken by the signal, or by the poll before it (which looks at the file): said either way.
  EXPECT_TRUE(WaitUntil([&] {
    const std::string log = stderrOf("replica-0");
    return log.find("took a new replica token from " + dir_.file("replica.token")) !=
               std::string::npos ||
           log.find("the replica token in " + dir_.file("replica.token") + " is the one in use") !=
               std::string::npos;
  })) << stderrOf("replica-0");
  addPincode(primary, "999126");
  EXPECT_EQ(WaitForStatus(replica, "/api/v1/pincodes/999126", 200), 200) << stderrOf("replica-0");
  // The watcher may serve the renamed file while the follower still syncs its directory, before
  // it clears the error.
  EXPECT_TRUE(WaitUntil([&] { return follow()["error"].is_null(); })) << follow().dump();
  EXPECT_NE(metrics().find("\npintag_follow_failing 0\n"), std::string::npos) << metrics();

  // The primary gone: the status says what failed in words (it said "did not answer: Connection").
  ASSERT_EQ(primary_->stop(SIGTERM, 30), 0);
  // A poll that met the primary closing says its answer broke off; the next ones find no one.
  EXPECT_TRUE(WaitUntil([&] {
    const json error = follow()["error"];
    return error.is_string() &&
           error.get<std::string>().find("did not answer: no connection could be made") !=
               std::string::npos;
  })) << follow().dump();
  EXPECT_EQ(StatusOf(replica.Get("/readyz")), 200);
}

// Rotating a replica token took a SIGHUP to every replica after the new token was written; one
// missed went on with the old token, refused once it was revoked. The file is looked at each poll.
TEST_F(ReplicaSetTest, AFollowerTakesATokenWrittenToItsFileWithoutASignal) {
  ServerProcess& follower = startFollower(0);
  ASSERT_TRUE(follower.ok());
  httplib::Client replica = LoopbackClient(follower.port());
  httplib::Client primary = LoopbackClient(primary_->port());
  const auto follow = [&] { return Body(replica.Get("/api/v1/registry"))["follow"]; };
  WaitUntil([&] { return !follow()["last_answer"].is_null(); });
  const json tokens = Body(primary.Get("/api/v1/tokens", Auth(admin_token_)));
  std::int64_t old_id = -1;
  for (const json& t : tokens["tokens"]) {
    if (t["role"] == "replica" && t["revoked_at"].is_null()) old_id = t["id"];
  }
  ASSERT_GT(old_id, 0);
  // A new token written as `pintag token create --out` writes it (replaced whole), the old one
  // revoked at once, and no signal.
  const json made =
      Body(primary.Post("/api/v1/tokens", Auth(admin_token_),
                        R"({"role": "replica", "label": "rotated"})", "application/json"));
  ASSERT_TRUE(made["secret"].is_string()) << made.dump();
  WriteFile(dir_.file("replica.token.new"), made["secret"].get<std::string>() + "\n");
  std::filesystem::rename(dir_.file("replica.token.new"), dir_.file("replica.token"));
  ASSERT_EQ(StatusOf(primary.Post("/api/v1/tokens/" + std::to_string(old_id) + "/revoke",
                                  Auth(admin_token_), "", "application/json")),
            200);
  // Served only through the new token: the old one is refused (401) from now on.
  addPincode(primary, "999127");
  EXPECT_EQ(WaitForStatus(replica, "/api/v1/pincodes/999127", 200), 200) << stderrOf("replica-0");
  EXPECT_TRUE(WaitUntil([&] { return follow()["error"].is_null(); })) << follow().dump();
  EXPECT_NE(stderrOf("replica-0").find("replica token was read again"), std::string::npos)
      << stderrOf("replica-0");

  // Written over in place (the same file, another size or time), the next token is taken too.
  const json third =
      Body(primary.Post("/api/v1/tokens", Auth(admin_token_),
                        R"({"role": "replica", "label": "rotated again"})", "application/json"));
  ASSERT_TRUE(third["secret"].is_string()) << third.dump();
  WriteFile(dir_.file("replica.token"), third["secret"].get<std::string>() + "\n");
  ASSERT_EQ(StatusOf(primary.Post("/api/v1/tokens/" + made["id"].dump() + "/revoke",
                                  Auth(admin_token_), "", "application/json")),
            200);
  addPincode(primary, "999128");
  EXPECT_EQ(WaitForStatus(replica, "/api/v1/pincodes/999128", 200), 200) << stderrOf("replica-0");
}

TEST_F(ReplicaSetTest, TwoReplicasServingOneFileLeaveEachOtherItsLinks) {
  const std::string snapshot = publishTo("shared.db");
  ServerProcess& first = startReadOnly(0, snapshot);
  ASSERT_TRUE(first.ok());
  // The first replica takes a newer snapshot, so it serves a link made after its start.
  httplib::Client primary("127.0.0.1", primary_->port());
  primary.set_read_timeout(30, 0);
  addPincode(primary, "999301");
  publishTo("shared.db");
  const std::int64_t published = RegistryVersionAt(primary_->port());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (RegistryVersionAt(first.port()) != published &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(RegistryVersionAt(first.port()), published);
  // The new version is served a moment before the link of the old one is removed: its files are
  // settled when they are one link and one lock file.
  std::set<std::string> first_files = ServingFiles(snapshot);
  while (first_files.size() != 2 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    first_files = ServingFiles(snapshot);
  }
  ASSERT_EQ(first_files.size(), 2U);

  // What ended runs leave: a link and a lock file nobody holds, a lock file not yet renamed,
  // and a link named as before tags.
  const std::string ended = snapshot + ".serving-00000000deadbeef";
  WriteFile(ended + ".lock", "");
  WriteFile(snapshot + ".serving-00000000cafef00d.lock.new", "");  // a start that crashed early
  ASSERT_EQ(::link(snapshot.c_str(), (ended + "-3").c_str()), 0);
  ASSERT_EQ(::link(snapshot.c_str(), (snapshot + ".serving-7").c_str()), 0);

  ServerProcess& second = startReadOnly(1, snapshot);
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(RegistryVersionAt(second.port()), published);
  const std::set<std::string> both = ServingFiles(snapshot);
  for (const std::string& name : first_files) EXPECT_EQ(both.count(name), 1U) << name;
  for (const char* gone :
       {"shared.db.serving-00000000deadbeef.lock", "shared.db.serving-00000000deadbeef-3",
        "shared.db.serving-00000000cafef00d.lock.new", "shared.db.serving-7"}) {
    EXPECT_EQ(both.count(gone), 0U) << gone;
  }
  // The first replica opens new connections on the link it serves: still there.
  EXPECT_EQ(LookupsFromManyClients(first.port()), 40);
  EXPECT_EQ(LookupsFromManyClients(second.port()), 40);

  // A replica that stops takes its own files away and leaves the other's.
  EXPECT_EQ(second.stop(SIGTERM, 30), 0);
  EXPECT_EQ(ServingFiles(snapshot), first_files);
  EXPECT_EQ(LookupsFromManyClients(first.port()), 40);
}

}  // namespace
}  // namespace pintag::serve_test
