#pragma once
// A primary and its read-only replicas as real `pintag serve` processes on loopback: a copy of a
// seeded database with a token of every role, the primary publishing snapshots (--snapshot), and
// replicas started on demand, each following the primary (--follow, replica token in a file) or
// serving a snapshot file it is handed.

#include <gtest/gtest.h>
#include <httplib.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "serve_fixture.hpp"

namespace pintag::serve_test {

class ReplicaSetTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;

  /// Starts replica `index` following the primary, on `port` (0: a free one); replaces one
  /// already running under that index. Fails the test when it does not start.
  ServerProcess& startFollower(std::size_t index, int port = 0);
  /// Starts replica `index` serving `snapshot` read-only, without following.
  ServerProcess& startReadOnly(std::size_t index, const std::string& snapshot);
  ServerProcess& replica(std::size_t index) { return *replicas_.at(index); }
  std::string replicaDb(std::size_t index) const;
  std::string replicaScanLog(std::size_t index) const;
  std::string primaryUrl() const;
  std::string stderrOf(const std::string& name) const;

  /// The registry version a server reports at GET /api/v1/registry; -1 when it does not answer.
  static std::int64_t RegistryVersionAt(int port);
  /// A snapshot of the primary's database now, renamed into place as `name` in the scratch
  /// directory; its path. Fails the test when it cannot be written.
  std::string publishTo(const std::string& name);
  /// Adds pincode `pin` with one office through the primary's API.
  void addPincode(httplib::Client& client, const std::string& pin);

  static httplib::Headers Auth(const std::string& token) {
    return {{"Authorization", "Bearer " + token}};
  }

  TempDir dir_;
  std::string primary_db_;
  std::string admin_token_, counter_token_, scanner_token_, replica_token_;
  std::unique_ptr<ServerProcess> primary_;
  std::vector<std::unique_ptr<ServerProcess>> replicas_;

 private:
  ServerProcess& startReplica(std::size_t index, std::vector<std::string> args, int port);
};

}  // namespace pintag::serve_test
