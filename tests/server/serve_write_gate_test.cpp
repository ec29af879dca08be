// Writes while another process holds the database's write lock (an import on the served file):
// the writers that wait for it may hold at most half of `pintag serve`'s worker threads, the rest
// are told within a second to come back (503, Retry-After), and lookups and the liveness probe
// keep being answered meanwhile. Nothing is written twice or lost: each 201 is a row, each 503 is
// none. (Writers that contend only with each other all get in: serve_routing_test's six
// concurrent plan writers.)

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "held_write_lock.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

struct WriteAnswer {
  int status = 0;
  std::string title;
  std::string retry_after;
  int finished_as = 0;  ///< 1 for the first answer to arrive, 2 for the second, ...
};

TEST_F(ServeTest, WritersWaitingOnAnotherProcessesLockLeaveHalfTheWorkersToEveryoneElse) {
  // The fixture's server runs 4 worker threads: 2 may write at once.
  HeldWriteLock lock(db_path_);
  constexpr int kWriters = 4;
  std::vector<WriteAnswer> answers(kWriters);
  std::atomic<int> finished{0};
  std::vector<std::thread> writers;
  writers.reserve(kWriters);
  for (int i = 0; i < kWriters; ++i) {
    writers.emplace_back([&, i] {
      httplib::Client writer("127.0.0.1", server_->port());
      writer.set_read_timeout(60, 0);
      const json body = {{"role", "scanner"}, {"label", "gate-" + std::to_string(i)}};
      const auto r = writer.Post("/api/v1/tokens", admin(), body.dump(), "application/json");
      WriteAnswer& answer = answers[static_cast<std::size_t>(i)];
      if (r) {
        answer.status = r->status;
        answer.retry_after = r->get_header_value("Retry-After");
        const json parsed = json::parse(r->body, nullptr, false);
        if (parsed.is_object() && parsed.contains("title")) answer.title = parsed["title"];
      }
      answer.finished_as = ++finished;
    });
  }
  // Two writers wait for the lock (up to 5 s); the other two wait for the gate, and are refused
  // once those have held it for a second. Asked meanwhile, the probe and a lookup are answered
  // by then at the latest, while the two writers still wait for the lock.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  httplib::Client other("127.0.0.1", server_->port());
  other.set_read_timeout(60, 0);
  const auto live = other.Get("/livez");
  const auto lookup = other.Get("/api/v1/pincodes/110001");
  const int finished_before_release = finished;
  // The lock is held until the two refusals are in: a writer that reached its worker late (a
  // busy machine) must still meet the gate, not a free lock.
  const auto refusals_due = std::chrono::steady_clock::now() + std::chrono::seconds(4);
  while (finished < 2 && std::chrono::steady_clock::now() < refusals_due) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  lock.release();
  for (std::thread& t : writers) t.join();

  ASSERT_TRUE(live);
  EXPECT_EQ(live->status, 200);
  ASSERT_TRUE(lookup);
  EXPECT_EQ(lookup->status, 200);
  // Answered once the two refused writers gave their threads back (their clients may count
  // their answers a moment after the probe's), not after a writer waiting for the lock gave up.
  EXPECT_LE(finished_before_release, 2)
      << "the probe and the lookup waited until a writer waiting for the lock gave up its thread";
  int refused = 0;
  int written = 0;
  for (const WriteAnswer& answer : answers) {
    if (answer.finished_as <= 2) {
      ++refused;
      EXPECT_EQ(answer.status, 503);
      EXPECT_EQ(answer.title, "Writers Busy");
      EXPECT_EQ(answer.retry_after, "1");
    } else {
      // Waited for the lock: written once it was released.
      EXPECT_EQ(answer.status, 201) << answer.title;
      written += answer.status == 201 ? 1 : 0;
    }
  }
  EXPECT_EQ(refused, 2);

  // Each 201 is one token, each 503 none; and with the lock gone, every writer is let in again.
  const json tokens = ExpectJson(client().Get("/api/v1/tokens", admin()));
  int gate_tokens = 0;
  for (const json& token : tokens["tokens"]) {
    if (token["label"].get<std::string>().starts_with("gate-")) ++gate_tokens;
  }
  EXPECT_EQ(gate_tokens, written);
  for (int i = 0; i < kWriters; ++i) {
    const json body = {{"role", "scanner"}, {"label", "after-" + std::to_string(i)}};
    EXPECT_EQ(client().Post("/api/v1/tokens", admin(), body.dump(), "application/json")->status,
              201);
  }
}

// A write that waited the whole busy timeout for another process's lock is told when to ask again.
TEST_F(ServeTest, AWriteThatOutwaitsTheLockIsToldToRetry) {
  HeldWriteLock lock(db_path_);
  const json body = {{"role", "scanner"}, {"label", "outwaited"}};
  const auto answer = client().Post("/api/v1/tokens", admin(), body.dump(), "application/json");
  const json problem = ExpectProblem(answer, 503);
  EXPECT_EQ(problem["title"], "Database Busy");
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->get_header_value("Retry-After"), "1");
  lock.release();
  const json tokens = ExpectJson(client().Get("/api/v1/tokens", admin()));
  for (const json& token : tokens["tokens"]) EXPECT_NE(token["label"], "outwaited");
}

}  // namespace
}  // namespace pintag::serve_test
