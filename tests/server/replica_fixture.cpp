#include "replica_fixture.hpp"

#include <filesystem>

#include "pintag/db/database.hpp"
#include "pintag/db/snapshot.hpp"
#include "pintag/db/tokens.hpp"

namespace pintag::serve_test {

void ReplicaSetTest::SetUp() {
  primary_db_ = dir_.file("primary.db");
  std::filesystem::copy_file(SeededTemplate(), primary_db_);
  {
    auto opened = db::OpenDatabase(primary_db_, {.create = false});
    ASSERT_TRUE(opened) << opened.error().message;
    db::Connection& connection = opened.value().connection;
    auto admin = db::CreateToken(connection, db::Role::kAdmin, "test admin");
    auto counter = db::CreateToken(connection, db::Role::kCounter, "test counter");
    auto scanner = db::CreateToken(connection, db::Role::kScanner, "test scanner");
    auto replica = db::CreateToken(connection, db::Role::kReplica, "test replicas");
    ASSERT_TRUE(admin && counter && scanner && replica);
    admin_token_ = admin->secret;
    counter_token_ = counter->secret;
    scanner_token_ = scanner->secret;
    replica_token_ = replica->secret;
  }
  WriteFile(dir_.file("replica.token"), replica_token_ + "\n");
  primary_ = std::make_unique<ServerProcess>(
      std::vector<std::string>{"--db", primary_db_, "--threads", "4", "--snapshot",
                               dir_.file("published.db")},
      dir_.file("primary.err"));
  ASSERT_TRUE(primary_->ok()) << "the primary did not start:\n" << stderrOf("primary");
}

void ReplicaSetTest::TearDown() {
  replicas_.clear();
  primary_.reset();
  if (HasFailure()) {
    std::cerr << "primary stderr:\n" << stderrOf("primary");
    for (std::size_t i = 0; i < 4; ++i) {
      const std::string err = stderrOf("replica-" + std::to_string(i));
      if (!err.empty()) std::cerr << "replica " << i << " stderr:\n" << err;
    }
  }
}

std::string ReplicaSetTest::replicaDb(std::size_t index) const {
  return dir_.file("replica-" + std::to_string(index) + ".db");
}

std::string ReplicaSetTest::replicaScanLog(std::size_t index) const {
  return dir_.file("replica-" + std::to_string(index) + "-scans.db");
}

std::string ReplicaSetTest::primaryUrl() const {
  return "http://127.0.0.1:" + std::to_string(primary_->port());
}

std::string ReplicaSetTest::stderrOf(const std::string& name) const {
  return ReadFile(dir_.file(name + ".err"));
}

ServerProcess& ReplicaSetTest::startReplica(std::size_t index, std::vector<std::string> args,
                                            int port) {
  if (replicas_.size() <= index) replicas_.resize(index + 1);
  replicas_[index].reset();
  // Threads beyond nginx's kept-alive connections (see docker/nginx/pintag.conf.template).
  args.insert(args.end(), {"--threads", "12", "--scan-log", replicaScanLog(index)});
  replicas_[index] = std::make_unique<ServerProcess>(
      args, dir_.file("replica-" + std::to_string(index) + ".err"), 60, port);
  EXPECT_TRUE(replicas_[index]->ok()) << "replica " << index << " did not start:\n"
                                      << stderrOf("replica-" + std::to_string(index));
  return *replicas_[index];
}

ServerProcess& ReplicaSetTest::startFollower(std::size_t index, int port) {
  return startReplica(index,
                      {"--db", replicaDb(index), "--follow", primaryUrl(), "--follow-token-file",
                       dir_.file("replica.token"), "--follow-interval-ms", "200"},
                      port);
}

ServerProcess& ReplicaSetTest::startReadOnly(std::size_t index, const std::string& snapshot) {
  return startReplica(index, {"--db", snapshot, "--read-only", "--primary", primaryUrl()}, 0);
}

std::int64_t ReplicaSetTest::RegistryVersionAt(int port) {
  httplib::Client client("127.0.0.1", port);
  client.set_read_timeout(10, 0);
  const auto r = client.Get("/api/v1/registry");
  if (!r || r->status != 200) return -1;
  const auto body = nlohmann::json::parse(r->body, nullptr, false);
  return body.is_discarded() ? -1 : body.value("registry_version", std::int64_t{-1});
}

std::string ReplicaSetTest::publishTo(const std::string& name) {
  std::string path = dir_.file(name);
  db::Connection live(primary_db_, {.create = false});
  const auto written = db::WriteSnapshot(live, path);
  EXPECT_TRUE(written.ok()) << written.error().message;
  return path;
}

void ReplicaSetTest::addPincode(httplib::Client& client, const std::string& pin) {
  const nlohmann::json body = {{"pincode", pin},
                               {"offices",
                                {{{"name", "Replica Nagar " + pin},
                                  {"district", "Testpur"},
                                  {"state", "Test State"},
                                  {"circle", "Test"},
                                  {"region", "T"},
                                  {"division", "TD"}}}}};
  const auto r =
      client.Post("/api/v1/pincodes", Auth(admin_token_), body.dump(), "application/json");
  ASSERT_TRUE(r) << httplib::to_string(r.error());
  ASSERT_EQ(r->status, 201) << r->body;
}

}  // namespace pintag::serve_test
