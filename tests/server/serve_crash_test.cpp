// SIGKILL a real `pintag serve` while it works, in three places: a batch label render, detections
// under load writing the scan log, registry writes through the API. After a restart the file
// passes PRAGMA integrity_check and foreign_key_check, every write the server acknowledged is
// there whole, nothing half-written is, and the same writes run again safely.

#include <sqlite3.h>

#include <atomic>
#include <set>
#include <thread>

#include "label_photo.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

/// Rows of a query on the database file, opened on its own (the server may be running).
std::vector<std::vector<std::string>> Query(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  std::vector<std::vector<std::string>> rows;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << "cannot open " << path;
    sqlite3_close(db);
    return rows;
  }
  sqlite3_busy_timeout(db, 5000);
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db);
  } else {
    while (sqlite3_step(statement) == SQLITE_ROW) {
      std::vector<std::string>& row = rows.emplace_back();
      for (int i = 0; i < sqlite3_column_count(statement); ++i) {
        const auto* text = sqlite3_column_text(statement, i);
        row.emplace_back(text ? reinterpret_cast<const char*>(text) : "NULL");
      }
    }
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return rows;
}

void ExpectIntact(const std::string& path) {
  const auto integrity = Query(path, "PRAGMA integrity_check");
  ASSERT_EQ(integrity.size(), 1U);
  EXPECT_EQ(integrity[0][0], "ok");
  EXPECT_TRUE(Query(path, "PRAGMA foreign_key_check").empty());
  // Every pincode has exactly one key and every key a pincode.
  EXPECT_EQ(Query(path,
                  "SELECT count(*) FROM pincodes p LEFT JOIN tag_keys k USING (pincode) "
                  "WHERE k.tag_key IS NULL")[0][0],
            "0");
}

/// `workers` threads call `work(client, worker, round)` until the server is gone; each true
/// return is an acknowledged write. Once `acknowledged` reaches `kill_after`, the server gets
/// SIGKILL while the others are still in flight. Returns when every worker has stopped.
class KillUnderLoad {
 public:
  using Work = std::function<bool(httplib::Client&, int worker, int round)>;

  KillUnderLoad(ServerProcess& server, int workers, int kill_after, const Work& work) {
    std::vector<std::thread> threads;
    threads.reserve(static_cast<std::size_t>(workers));
    // Read once here: the worker that kills the server changes `server` while others still run.
    const pid_t pid = server.pid();
    for (int w = 0; w < workers; ++w) {
      threads.emplace_back([&, w] {
        httplib::Client client("127.0.0.1", server.port());
        client.set_read_timeout(60, 0);
        for (int round = 0; !killed_ && round < kMaxRounds; ++round) {
          if (work(client, w, round)) {
            if (++acknowledged_ >= kill_after && !killed_.exchange(true)) server.stop(SIGKILL, 10);
          } else if (pid <= 0 || ::kill(pid, 0) != 0) {
            break;  // the server is gone (a failed call while it lived is retried)
          }
        }
      });
    }
    for (std::thread& t : threads) t.join();
  }
  int acknowledged() const { return acknowledged_; }

 private:
  static constexpr int kMaxRounds = 2000;  // a server that never acknowledges ends the test
  std::atomic<int> acknowledged_{0};
  std::atomic<bool> killed_{false};
};

TEST_F(ServeTest, SigkillDuringBatchLabelRendersLeavesTheRegistryIntact) {
  const std::string before = Query(db_path_, "SELECT count(*) FROM tag_keys")[0][0];
  json pins = json::array();
  for (const char* pin : {"110001", "560001", "400001", "700001", "600001", "500001"})
    pins.push_back(pin);
  const std::string batch = json{{"pincodes", pins}, {"size", "a6"}}.dump();
  const httplib::Headers auth = counter();
  KillUnderLoad load(*server_, 4, 3, [&](httplib::Client& c, int, int) {
    const auto r = c.Post("/api/v1/labels", auth, batch, "application/json");
    return r && r->status == 200 && r->body.rfind("%PDF", 0) == 0;
  });
  EXPECT_GE(load.acknowledged(), 3);
  ExpectIntact(db_path_);
  startServer();
  ExpectIntact(db_path_);
  EXPECT_EQ(Query(db_path_, "SELECT count(*) FROM tag_keys")[0][0], before);
  const auto again = client().Post("/api/v1/labels", counter(), batch, "application/json");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 200);
}

TEST_F(ServeTest, SigkillDuringDetectionsKeepsEveryAcknowledgedScanWhole) {
  const Photo photo = PhotographLabel(client(), counter(), "110001", 20);
  ASSERT_FALSE(photo.jpeg.empty());
  const httplib::Headers auth = scanner();
  KillUnderLoad load(*server_, 4, 6, [&](httplib::Client& c, int, int) {
    const auto r = c.Post("/api/v1/detect", auth, photo.jpeg, "image/jpeg");
    return r && r->status == 200;
  });
  ExpectIntact(db_path_);
  const auto rows = Query(db_path_, "SELECT result_json, image_bytes, image_width FROM scan_log");
  // Each acknowledged scan was committed before its answer was sent, unless a write took over a
  // second (a loaded machine): then scans are answered first and held, the server says so, and a
  // kill loses them by design. A scan killed before its commit is absent, never half there.
  if (ReadFile(dir_.file("stderr.log")).find("scans are answered before they are written") ==
      std::string::npos) {
    EXPECT_GE(rows.size(), static_cast<std::size_t>(load.acknowledged()));
  }
  for (const auto& row : rows) {
    const json result = json::parse(row[0], nullptr, false);
    ASSERT_FALSE(result.is_discarded()) << row[0];
    EXPECT_EQ(result["tag_count"], 1) << row[0];
    EXPECT_EQ(row[1], std::to_string(photo.jpeg.size()));
    EXPECT_EQ(row[2], "1920");
  }
  startServer();
  ExpectIntact(db_path_);
  const auto r = client().Post("/api/v1/detect", scanner(), photo.jpeg, "image/jpeg");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(Query(db_path_, "SELECT count(*) FROM scan_log")[0][0],
            std::to_string(rows.size() + 1));
}

/// Pincodes no seed holds (Indian pincodes stop below 860000).
std::string NewPincode(int worker, int round) {
  return std::to_string(990000 + worker * 2000 + round);
}

json PincodeBody(const std::string& pin) {
  return {{"pincode", pin},
          {"offices",
           {{{"name", "Crash Test BO"},
             {"division", "Dv"},
             {"region", "Rg"},
             {"circle", "Ci"},
             {"district", "D"},
             {"state", "S"}}}}};
}

/// A plan CSV of 300 rules, prefixes 100 … 399, plus the fallback.
std::string PlanCsv(int round) {
  std::string csv = "prefix,bin\n*,Z" + std::to_string(round) + "\n";
  for (int prefix = 100; prefix < 400; ++prefix) {
    csv += std::to_string(prefix) + ",B" + std::to_string(prefix % 7) + "\n";
  }
  return csv;
}

TEST_F(ServeTest, SigkillDuringRegistryWritesLeavesEachWriteWholeOrAbsent) {
  const httplib::Headers auth = admin();
  std::mutex mutex;
  std::vector<std::string> added;
  KillUnderLoad load(*server_, 4, 40, [&](httplib::Client& c, int worker, int round) {
    if (worker == 3) {  // one worker rewrites whole sort plans
      const auto r = c.Put("/api/v1/sortplans/crash-" + std::to_string(round % 3), auth,
                           PlanCsv(round), "text/csv");
      return r && (r->status == 200 || r->status == 201);
    }
    const std::string pin = NewPincode(worker, round);
    const json body = PincodeBody(pin);
    const auto r = c.Post("/api/v1/pincodes", auth, body.dump(), "application/json");
    if (!r || r->status != 201) return false;
    const std::lock_guard lock(mutex);
    added.push_back(pin);
    return true;
  });
  ExpectIntact(db_path_);
  EXPECT_GE(added.size(), 10U) << "the load did not write pincodes";
  // Every acknowledged pincode is there with its key and office.
  for (const std::string& pin : added) {
    const auto row = Query(db_path_,
                           "SELECT count(*) FROM pincodes JOIN tag_keys USING (pincode) JOIN "
                           "offices USING (pincode) WHERE pincode = " +
                               pin);
    EXPECT_EQ(row[0][0], "1") << pin;
  }
  // Every plan there has all its rules: none was cut in half.
  for (const auto& plan : Query(db_path_,
                                "SELECT p.name, count(r.prefix) FROM sort_plans p LEFT JOIN "
                                "sort_rules r ON r.plan_id = p.id WHERE p.name LIKE 'crash-%' "
                                "GROUP BY p.id")) {
    EXPECT_EQ(plan[1], "300") << plan[0];
  }

  // Restart and run every write again: what is there answers 409, what is not is added. An
  // acknowledged write must be there (409); one cut by the kill may or may not have committed.
  startServer();
  ExpectIntact(db_path_);
  const std::set<std::string> acknowledged(added.begin(), added.end());
  for (int worker = 0; worker < 3; ++worker) {
    for (int round = 0; round < 20; ++round) {
      const std::string pin = NewPincode(worker, round);
      const json body = PincodeBody(pin);
      const auto r = client().Post("/api/v1/pincodes", admin(), body.dump(), "application/json");
      ASSERT_TRUE(r);
      if (acknowledged.contains(pin)) {
        EXPECT_EQ(r->status, 409) << pin << " was acknowledged, then lost: " << r->body;
      } else {
        EXPECT_TRUE(r->status == 201 || r->status == 409) << r->status << " " << r->body;
      }
    }
  }
  const auto plan = client().Put("/api/v1/sortplans/crash-0", admin(), PlanCsv(0), "text/csv");
  ASSERT_TRUE(plan);
  EXPECT_LT(plan->status, 300);
  ExpectIntact(db_path_);
}

}  // namespace
}  // namespace pintag::serve_test
