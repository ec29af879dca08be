// The scaled-out topology without containers: Debian's nginx from the Docker image's config
// template in front of one primary and three following replicas, all on loopback. Mixed traffic
// through nginx while one replica is killed with SIGKILL and started again: every request gets
// its correct answer. Then a pincode written through nginx reaches every replica.
//
// One thing no proxy can hide: a response the killed replica had begun to send (nginx has passed
// its headers on) is cut, and nginx can only close the client's connection. The clients here do
// what a scanner does with a dropped connection: send the same request once more. At most one
// request per client can be in flight on the killed replica, so at most that many are cut.

#include <signal.h>

#include <atomic>
#include <thread>

#include "label_photo.hpp"
#include "nginx_process.hpp"
#include "pintag/db/sqlite.hpp"
#include "pintag/test/loopback_socket.hpp"
#include "replica_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

json Body(const httplib::Result& r) {
  if (!r) return {};
  const json body = json::parse(r->body, nullptr, false);
  return body.is_discarded() ? json() : body;
}

std::int64_t ScanRows(const std::string& path) {
  db::Connection connection(path, {.create = false, .read_only = true});
  return connection.queryInt64("SELECT count(*) FROM scan_log");
}

/// What the load saw.
struct Tally {
  std::atomic<int> sent{0};
  std::atomic<int> right{0};
  std::atomic<int> wrong{0};
  std::atomic<int> socket_errors{0};  ///< no answer even when sent again
  std::atomic<int> cut{0};            ///< first try cut, second answered
  std::atomic<int> detections{0};
  std::atomic<int> answered_while_down{0};
};

TEST_F(ReplicaSetTest, NginxWithThreeReplicasLosesNothingWhenOneIsKilledUnderLoad) {
  for (std::size_t i = 0; i < 3; ++i) ASSERT_TRUE(startFollower(i).ok());
  std::vector<int> replica_ports;
  for (std::size_t i = 0; i < 3; ++i) replica_ports.push_back(replica(i).port());
  NginxProcess nginx(dir_.path() / "nginx", primary_->port(), replica_ports);
  ASSERT_TRUE(nginx.ok()) << nginx.error();

  httplib::Client primary("127.0.0.1", primary_->port());
  const Photo photo = PhotographLabel(primary, Auth(counter_token_), "110001", 20,
                                      scene::Camera{700, 700, 400, 300, 800, 600});
  ASSERT_FALSE(photo.jpeg.empty());

  Tally tally;
  std::atomic<bool> stop{false}, down{false};
  // Each request with the answer it must get; a 404 is right for a pincode that does not exist.
  const auto send_once = [&](httplib::Client& client, int n, bool& right) {
    httplib::Result r{nullptr, httplib::Error::Unknown};
    right = false;
    switch (n % 5) {
      case 0: {
        r = client.Get("/api/v1/pincodes/110001");
        right = r && r->status == 200 && Body(r)["key"] == 11684;
        break;
      }
      case 1: {
        r = client.Get("/api/v1/route/560001?plan=default");
        right = r && r->status == 200 && Body(r)["bin"] == "56";
        break;
      }
      case 2: {
        r = client.Get("/api/v1/labels/560001.png?dpi=72", Auth(counter_token_));
        right = r && r->status == 200 && r->body.rfind("\x89PNG", 0) == 0;
        break;
      }
      case 3: {
        r = client.Post("/api/v1/detect", Auth(scanner_token_), photo.jpeg, "image/jpeg");
        const json out = Body(r);
        right = r && r->status == 200 && out["tags"].size() == 1 &&
                out["tags"][0]["pincode"] == "110001" && out["tags"][0]["bin"] == "11";
        if (right) ++tally.detections;
        break;
      }
      default: {
        r = client.Get("/api/v1/pincodes/999999");
        right = r && r->status == 404 &&
                r->get_header_value("Content-Type") == "application/problem+json";
        break;
      }
    }
    return r;
  };
  const auto one_request = [&](httplib::Client& client, int n) {
    bool right = false;
    httplib::Result r = send_once(client, n, right);
    if (!r) {
      r = send_once(client, n, right);
      if (r) ++tally.cut;
    }
    ++tally.sent;
    if (!r) {
      ++tally.socket_errors;
      ADD_FAILURE() << "request " << n % 5 << ": " << httplib::to_string(r.error());
    } else if (right) {
      ++tally.right;
      if (down) ++tally.answered_while_down;
    } else {
      ++tally.wrong;
      ADD_FAILURE() << "request " << n % 5 << " answered " << r->status << ": "
                    << r->body.substr(0, 300);
    }
  };
  std::vector<std::thread> clients;
  clients.reserve(6);
  for (int t = 0; t < 6; ++t) {
    clients.emplace_back([&, t] {
      httplib::Client client("127.0.0.1", nginx.port());
      client.set_read_timeout(60, 0);
      for (int n = t; !stop; ++n) one_request(client, n);
    });
  }
  // One deadline for the whole load, and one below for replication, so that a stuck test ends in
  // its own failure messages (and nginx's log) well inside ctest's timeout for test_serve.
  const auto load_deadline = Clock::now() + std::chrono::seconds(150);
  const auto wait_for = [&](int count) {
    while (tally.sent < count && Clock::now() < load_deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  };
  // Killed mid-load, left down while the load goes on, started again on its port.
  wait_for(100);
  const int killed_port = replica(1).port();
  EXPECT_EQ(replica(1).stop(SIGKILL), 128 + SIGKILL);
  down = true;
  wait_for(tally.sent + 150);
  down = false;
  ASSERT_TRUE(startFollower(1, killed_port).ok());
  wait_for(tally.sent + 100);
  stop = true;
  for (std::thread& c : clients) c.join();

  EXPECT_EQ(tally.wrong.load(), 0);
  EXPECT_EQ(tally.socket_errors.load(), 0);
  EXPECT_LE(tally.cut.load(), 6) << "more cut responses than requests in flight at the kill";
  EXPECT_EQ(tally.right.load(), tally.sent.load());
  EXPECT_GE(tally.sent.load(), 350);
  EXPECT_GE(tally.answered_while_down.load(), 100);
  // Every detection was logged by the replica that made it, none by the primary. A detection
  // retried after the kill may have been logged by the killed replica too.
  // The live replicas' last rows may be written a moment after their answers.
  std::int64_t logged = 0;
  for (const auto deadline = Clock::now() + std::chrono::seconds(30);
       logged < tally.detections.load() && Clock::now() < deadline;
       std::this_thread::sleep_for(std::chrono::milliseconds(50))) {
    logged = 0;
    for (std::size_t i = 0; i < 3; ++i) logged += ScanRows(replicaScanLog(i));
  }
  // Unless the killed replica's log fell behind (a write over a second, which it logs): scans it
  // then answered were held, not written, and are lost with it by design.
  if (stderrOf("replica-1").find("scans are answered before they are written") ==
      std::string::npos) {
    EXPECT_GE(logged, tally.detections.load());
  }
  EXPECT_EQ(ScanRows(primary_db_), 0);

  // A write through nginx goes to the primary (a replica would answer 403) and reaches every
  // replica; the deadline only keeps a broken follower from hanging the test.
  httplib::Client front("127.0.0.1", nginx.port());
  addPincode(front, "999321");
  EXPECT_EQ(Body(front.Get("/api/v1/registry"))["role"], "replica");
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  for (std::size_t i = 0; i < 3; ++i) {
    httplib::Client client("127.0.0.1", replica(i).port());
    int status = 0;
    while (status != 200 && Clock::now() < deadline) {
      const auto r = client.Get("/api/v1/pincodes/999321");
      status = r ? r->status : 0;
      if (status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_EQ(status, 200) << "replica " << i;
  }
  if (HasFailure()) std::cerr << "nginx:\n" << nginx.logs().substr(0, 20000);
}

/// Asserts `r` is a problem+json answer from nginx with this status; returns its body.
json ExpectNginxProblem(const httplib::Result& r, int status) {
  if (!r) {
    ADD_FAILURE() << "no answer: " << httplib::to_string(r.error());
    return {};
  }
  EXPECT_EQ(r->status, status) << r->body.substr(0, 300);
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/problem+json");
  EXPECT_EQ(r->get_header_value("Server"), "nginx");  // without its version
  json body = Body(r);
  EXPECT_EQ(body["status"], status) << r->body.substr(0, 300);
  EXPECT_TRUE(body["title"].is_string() && body["detail"].is_string()) << r->body.substr(0, 300);
  EXPECT_FALSE(r->get_header_value("X-Request-Id").empty());
  return body;
}

// Through nginx, an answer nginx makes itself (a body over the limit, no server up) reads as the
// server's own problem+json; every request carries one id, in the answer, in nginx's log (which
// holds the client's address) and in the server's log.
TEST_F(ReplicaSetTest, NginxAnswersItsOwnRefusalsAsProblemsAndCarriesOneRequestId) {
  ASSERT_TRUE(startFollower(0).ok());
  NginxProcess nginx(dir_.path() / "nginx", primary_->port(), {replica(0).port()});
  ASSERT_TRUE(nginx.ok()) << nginx.error();
  httplib::Client front("127.0.0.1", nginx.port());

  const auto looked_up = front.Get("/api/v1/pincodes/110001");
  ASSERT_TRUE(looked_up);
  ASSERT_EQ(looked_up->status, 200);
  // An HTTP/1.0 request names no host (the nginx image's HEALTHCHECK sends one): nginx still
  // passes the servers one, who refuse an HTTP/1.1 request without it.
  const std::string health = test::SendRaw(nginx.port(), "GET /readyz HTTP/1.0\r\n\r\n", 10);
  EXPECT_EQ(health.rfind("HTTP/1.1 200", 0), 0U) << health.substr(0, 300);
  const std::string id = looked_up->get_header_value("X-Request-Id");
  EXPECT_EQ(id.size(), 32U) << id;
  const auto own = front.Get("/api/v1/pincodes/560001", {{"X-Request-Id", "scanner-7-0042"}});
  ASSERT_TRUE(own);
  EXPECT_EQ(own->get_header_value("X-Request-Id"), "scanner-7-0042");
  // Both in each log: nginx writes its log at most 1 s late (flush=1s).
  const auto logged_in_both = [&](const std::string& wanted) {
    for (int attempt = 0; attempt < 50; ++attempt) {
      if (nginx.logs().find("id=" + wanted) != std::string::npos &&
          stderrOf("replica-0").find("id=" + wanted) != std::string::npos) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  };
  EXPECT_TRUE(logged_in_both(id)) << nginx.logs() << stderrOf("replica-0");
  EXPECT_TRUE(logged_in_both("scanner-7-0042"));
  // An id the server would not keep is replaced by nginx's own, which both logs then share: with
  // spaces it would also have written fields of the client's into nginx's log line.
  const auto forged = front.Get("/api/v1/pincodes/560001",
                                {{"X-Request-Id", "x upstream=10.9.9.9:1 upstream_status=200"}});
  ASSERT_TRUE(forged);
  const std::string replaced = forged->get_header_value("X-Request-Id");
  EXPECT_EQ(replaced.size(), 32U) << replaced;
  EXPECT_TRUE(logged_in_both(replaced));
  EXPECT_EQ(nginx.logs().find("10.9.9.9"), std::string::npos) << nginx.logs();

  // One byte over the documented 25 MiB: refused by nginx before any server sees it.
  const std::string over(std::size_t{25} << 20 | 1, 'x');
  const json too_large = ExpectNginxProblem(
      front.Post("/api/v1/detect", Auth(scanner_token_), over, "image/jpeg"), 413);
  EXPECT_NE(too_large.dump().find("26214400 bytes"), std::string::npos) << too_large.dump();

  // No replica up: nginx has nobody to ask.
  EXPECT_EQ(replica(0).stop(SIGKILL), 128 + SIGKILL);
  httplib::Client again("127.0.0.1", nginx.port());
  ExpectNginxProblem(again.Get("/api/v1/pincodes/110001"), 502);
  // The servers' own refusals pass through as they were: a write still reaches the primary.
  const json refused = Body(again.Post("/api/v1/pincodes", "{}", "application/json"));
  EXPECT_EQ(refused["status"], 401) << refused.dump();
  if (HasFailure()) std::cerr << "nginx:\n" << nginx.logs().substr(0, 20000);
}

}  // namespace
}  // namespace pintag::serve_test
