// The operator's view of a real `pintag serve`: one access line per request on stderr (text or
// JSON), the X-Request-Id echoed, failures logged under that id and written to the scan log,
// every serve flag also from a PINTAG_* variable, and the process_* metrics.

#include <sqlite3.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <thread>

#include "pintag/db/database.hpp"
#include "pintag/db/scan_log.hpp"
#include "pintag/test/loopback_socket.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

/// The server's stderr lines that mention `needle`, waiting up to 5 s until there are at least
/// `expected` of them (the access line is written after the response, so it may trail the
/// client's read by a moment; an error line logged before the response does not mean it is there).
std::vector<std::string> LogLines(const std::string& file, const std::string& needle,
                                  std::size_t expected = 1) {
  std::vector<std::string> found;
  for (int attempt = 0; attempt < 500 && found.size() < expected; ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    found.clear();
    std::istringstream text(ReadFile(file));
    for (std::string line; std::getline(text, line);) {
      if (line.find(needle) != std::string::npos) found.push_back(line);
    }
  }
  return found;
}

/// Runs `sql` on the served database through a connection of its own, as another process would:
/// a real storage failure under the running server. SQLite's result code.
int ExecuteBehindTheServer(const std::string& path, const char* sql) {
  sqlite3* raw = nullptr;
  if (sqlite3_open(path.c_str(), &raw) != SQLITE_OK) {
    sqlite3_close(raw);
    return SQLITE_CANTOPEN;
  }
  sqlite3_busy_timeout(raw, 5000);
  const int rc = sqlite3_exec(raw, sql, nullptr, nullptr, nullptr);
  sqlite3_close(raw);
  return rc;
}

class ServeLogTest : public ServeTest {
 protected:
  std::string stderrFile() const { return dir_.file("stderr.log"); }
};

TEST_F(ServeLogTest, EveryRequestGetsOneAccessLineWithItsEchoedRequestId) {
  auto ok = client().Get("/api/v1/pincodes/110001", {{"X-Request-Id", "lookup-42"}});
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
  EXPECT_EQ(ok->get_header_value("X-Request-Id"), "lookup-42");
  const std::vector<std::string> lines = LogLines(stderrFile(), "id=lookup-42");
  ASSERT_EQ(lines.size(), 1U) << ReadFile(stderrFile());
  const std::string& line = lines[0];
  EXPECT_NE(line.find(" info access "), std::string::npos) << line;
  EXPECT_NE(line.find("client=127.0.0.1"), std::string::npos) << line;
  EXPECT_NE(line.find("method=GET"), std::string::npos) << line;
  EXPECT_NE(line.find("path=/api/v1/pincodes/110001"), std::string::npos) << line;
  EXPECT_NE(line.find("status=200"), std::string::npos) << line;
  EXPECT_NE(line.find("bytes=" + std::to_string(ok->body.size())), std::string::npos) << line;
  EXPECT_TRUE(std::regex_search(line, std::regex(R"( ms=[0-9.]+)"))) << line;
  EXPECT_TRUE(
      std::regex_match(line.substr(0, 24), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z)")))
      << line;

  auto missing = client().Get("/api/v1/no-such-route", {{"X-Request-Id", "missing-1"}});
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  EXPECT_EQ(missing->get_header_value("X-Request-Id"), "missing-1");
  const auto missing_lines = LogLines(stderrFile(), "id=missing-1");
  ASSERT_EQ(missing_lines.size(), 1U);
  EXPECT_NE(missing_lines[0].find("status=404"), std::string::npos) << missing_lines[0];

  // A HEAD answer sends no body, so it logs none (it logged the body GET would have sent).
  auto head = client().Head("/api/v1/pincodes/110001", {{"X-Request-Id", "head-1"}});
  ASSERT_TRUE(head);
  EXPECT_EQ(head->status, 200);
  const auto head_lines = LogLines(stderrFile(), "id=head-1");
  ASSERT_EQ(head_lines.size(), 1U);
  EXPECT_NE(head_lines[0].find(" bytes=0 "), std::string::npos) << head_lines[0];
}

// An answer the client went away from is logged with what the server answered and cut_off=true:
// a 200 alone would say the client got it. The file is larger than loopback's socket buffers
// can hold, so the server is still writing when the client resets the connection.
TEST_F(ServeLogTest, AnAnswerTheClientLeftIsLoggedAsCutOff) {
  const std::filesystem::path web = dir_.path() / "web";
  std::filesystem::create_directories(web);
  WriteFile(web / "big.bin", std::string(std::size_t{48} << 20, 'x'));
  startServer({"--web", web.string()});

  auto whole = client().Get("/big.bin", {{"X-Request-Id", "read-whole"}});
  ASSERT_TRUE(whole);
  EXPECT_EQ(whole->body.size(), std::size_t{48} << 20);
  const auto whole_lines = LogLines(stderrFile(), "id=read-whole");
  ASSERT_EQ(whole_lines.size(), 1U);
  EXPECT_EQ(whole_lines[0].find("cut_off"), std::string::npos) << whole_lines[0];

  const int fd = test::ConnectLoopback(server_->port());
  ASSERT_GE(fd, 0);
  // A small receive buffer, so that a host whose loopback buffers are tuned larger than the file
  // still leaves the server writing.
  const int small_buffer = 64 << 10;
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small_buffer, sizeof small_buffer);
  ASSERT_TRUE(test::SendAll(fd, "GET /big.bin HTTP/1.1\r\nHost: x\r\nX-Request-Id: left\r\n\r\n"));
  const std::string head = test::ReceiveUntil(
      fd, 30, [](const std::string& in) { return in.find("\r\n\r\n") != std::string::npos; });
  ASSERT_EQ(head.rfind("HTTP/1.1 200", 0), 0U) << head.substr(0, 200);
  const linger reset_on_close{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_LINGER, &reset_on_close, sizeof reset_on_close);
  ::close(fd);
  const auto left_lines = LogLines(stderrFile(), "id=left");
  ASSERT_EQ(left_lines.size(), 1U) << ReadFile(stderrFile());
  EXPECT_NE(left_lines[0].find("status=200"), std::string::npos) << left_lines[0];
  EXPECT_NE(left_lines[0].find("cut_off=true"), std::string::npos) << left_lines[0];
  // The server goes on serving.
  EXPECT_EQ(client().Get("/livez")->status, 200);
}

TEST_F(ServeLogTest, AnInsaneOrMissingRequestIdIsReplacedByARandomOne) {
  const std::regex generated("[0-9a-f]{32}");
  for (const std::string& bad : {std::string("has spaces in it"), std::string(129, 'a'),
                                 std::string("quote\"and=equals"), std::string()}) {
    httplib::Headers headers;
    if (!bad.empty()) headers.emplace("X-Request-Id", bad);
    auto r = client().Get("/livez", headers);
    ASSERT_TRUE(r);
    EXPECT_TRUE(std::regex_match(r->get_header_value("X-Request-Id"), generated))
        << "for '" << bad << "': " << r->get_header_value("X-Request-Id");
  }
  auto a = client().Get("/livez");
  auto b = client().Get("/livez");
  ASSERT_TRUE(a && b);
  EXPECT_NE(a->get_header_value("X-Request-Id"), b->get_header_value("X-Request-Id"));
}

TEST_F(ServeLogTest, QueryStringsAndTokensStayOutOfTheLog) {
  auto r = client().Get("/api/v1/pincodes?q=secret-query-value&limit=1&token=hunter2",
                        Auth(counter_token_));
  ASSERT_TRUE(r);
  const std::string id = r->get_header_value("X-Request-Id");
  ASSERT_EQ(LogLines(stderrFile(), "id=" + id).size(), 1U);
  const std::string log = ReadFile(stderrFile());
  EXPECT_EQ(log.find("secret-query-value"), std::string::npos);
  EXPECT_EQ(log.find("hunter2"), std::string::npos);
  EXPECT_EQ(log.find(counter_token_), std::string::npos);
}

TEST_F(ServeLogTest, AuthenticatedRequestsNameTheTokenIdNotItsSecret) {
  auto r = client().Get("/api/v1/tokens", admin());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  const auto lines = LogLines(stderrFile(), "id=" + r->get_header_value("X-Request-Id"));
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_TRUE(std::regex_search(lines[0], std::regex(R"( token=\d+$)"))) << lines[0];
  EXPECT_EQ(lines[0].find(admin_token_), std::string::npos);
  // A valid token refused for its role (403) is named too: which counter tried an admin route.
  auto refused = client().Get("/api/v1/tokens", Auth(counter_token_));
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403);
  const auto refused_lines =
      LogLines(stderrFile(), "id=" + refused->get_header_value("X-Request-Id"));
  ASSERT_EQ(refused_lines.size(), 1U);
  EXPECT_TRUE(std::regex_search(refused_lines[0], std::regex(R"( status=403 .* token=\d+$)")))
      << refused_lines[0];
  EXPECT_EQ(refused_lines[0].find(counter_token_), std::string::npos);
}

TEST_F(ServeLogTest, JsonFormatWritesOneObjectPerLine) {
  startServer({"--log-format", "json"});
  auto r = client().Get("/api/v1/pincodes/560001?x=1", {{"X-Request-Id", "json-7"}});
  ASSERT_TRUE(r);
  const auto lines = LogLines(stderrFile(), "\"json-7\"");
  ASSERT_EQ(lines.size(), 1U);
  const json line = json::parse(lines[0], nullptr, false);
  ASSERT_FALSE(line.is_discarded()) << lines[0];
  EXPECT_EQ(line["event"], "access");
  EXPECT_EQ(line["level"], "info");
  EXPECT_EQ(line["id"], "json-7");
  EXPECT_EQ(line["method"], "GET");
  EXPECT_EQ(line["path"], "/api/v1/pincodes/560001");
  EXPECT_EQ(line["status"], r->status);
  EXPECT_EQ(line["bytes"], r->body.size());
  EXPECT_EQ(line["client"], "127.0.0.1");
  EXPECT_TRUE(line["ms"].is_number());
  EXPECT_TRUE(line["time"].is_string());
}

// Behind nginx every request's peer is nginx; the client it forwarded for is in X-Forwarded-For,
// believed only from the proxies the operator named. A client writing the header itself does not
// change its name in the log.
TEST_F(ServeLogTest, TheClientATrustedProxyForwardedForIsLoggedWithTheProxy) {
  using ClientAndProxy = std::pair<std::string, std::string>;
  const auto client_and_proxy = [&](const std::string& id, const std::string& forwarded_for) {
    auto r = client().Get("/livez", {{"X-Request-Id", id}, {"X-Forwarded-For", forwarded_for}});
    EXPECT_TRUE(r);
    const auto lines = LogLines(stderrFile(), "\"" + id + "\"");
    EXPECT_EQ(lines.size(), 1U);
    const json line = lines.empty() ? json() : json::parse(lines[0], nullptr, false);
    return ClientAndProxy{line.value("client", ""), line.value("proxy", "")};
  };
  startServer({"--log-format", "json"});
  EXPECT_EQ(client_and_proxy("untrusted", "198.51.100.7"), ClientAndProxy("127.0.0.1", ""));

  // Two flags, the second a list, as PINTAG_TRUSTED_PROXY gives one.
  startServer({"--log-format", "json", "--trusted-proxy", "127.0.0.1", "--trusted-proxy",
               "10.0.0.0/8,fd00::/8"});
  EXPECT_EQ(client_and_proxy("forwarded", "198.51.100.7"),
            ClientAndProxy("198.51.100.7", "127.0.0.1"));
  // What the client wrote before nginx appended its address is not believed.
  EXPECT_EQ(client_and_proxy("spoofed", "6.6.6.6, 198.51.100.7, 10.1.2.3"),
            ClientAndProxy("198.51.100.7", "127.0.0.1"));
  // A client on nginx's own host is still one nginx forwarded for (the Docker test's case).
  EXPECT_EQ(client_and_proxy("same-host", "127.0.0.1"), ClientAndProxy("127.0.0.1", "127.0.0.1"));
  EXPECT_EQ(client_and_proxy("garbage", "<script>alert(1)</script>"),
            ClientAndProxy("127.0.0.1", ""));

  const CommandResult refused =
      RunPintag("serve --port 0 --trusted-proxy nginx --db " + dir_.file("never.db"));
  EXPECT_EQ(refused.status, 2) << refused.out;
  EXPECT_NE(refused.out.find("--trusted-proxy 'nginx' is not an IPv4 or IPv6 address"),
            std::string::npos)
      << refused.out;
  EXPECT_FALSE(std::filesystem::exists(dir_.file("never.db")));
}

TEST_F(ServeLogTest, AServerFailureIsLoggedWithTheRequestIdAndWrittenToTheScanLog) {
  // A real storage failure under the running server: the sort plans table disappears, so
  // looking up the plan for /detect fails with an SQLite error the client must not see.
  ASSERT_EQ(ExecuteBehindTheServer(db_path_, "PRAGMA foreign_keys=OFF; DROP TABLE sort_plans;"),
            SQLITE_OK);
  httplib::MultipartFormDataItems form = {{"image", "not looked at", "p.jpg", "image/jpeg"}};
  httplib::Headers headers = scanner();
  headers.emplace("X-Request-Id", "detect-fails-1");
  auto r = client().Post("/api/v1/detect", headers, form);
  const json problem = ExpectProblem(r, 500);
  EXPECT_EQ(problem["detail"].get<std::string>().find("sort_plans"), std::string::npos)
      << "the SQL error reached the client: " << problem.dump();

  const auto lines = LogLines(stderrFile(), "detect-fails-1", 2);
  ASSERT_EQ(lines.size(), 2U) << ReadFile(stderrFile());
  EXPECT_NE(lines[0].find(" error error id=detect-fails-1"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("POST /api/v1/detect: 500"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("status=500"), std::string::npos) << lines[1];
  EXPECT_NE(ReadFile(stderrFile()).find("sort_plans"), std::string::npos)
      << "the operator should see SQLite's message";

  ScanRowsOnceThereAre(db_path_, 1);
  auto opened = db::OpenDatabase(db_path_, {.create = false});
  ASSERT_TRUE(opened);
  auto scans = db::RecentScans(opened.value().connection, 1);
  ASSERT_TRUE(scans);
  ASSERT_EQ(scans->size(), 1U);
  const json result = json::parse(scans->front().result_json);
  EXPECT_EQ(result["error"]["status"], 500) << scans->front().result_json;
}

// With --log-format json, the line saying why serve could not start is JSON too: it was written
// as "pintag: …" text, the one line of such a run a log pipeline could not parse.
TEST_F(ServeLogTest, WithJsonLogsAServeThatCannotStartSaysWhyInJson) {
  const CommandResult busy = RunPintag("serve --log-format json --bind 127.0.0.1 --port " +
                                       std::to_string(server_->port()) + " --db " + db_path_);
  EXPECT_EQ(busy.status, 1) << busy.out;
  std::istringstream lines(busy.out);
  bool said = false;
  for (std::string line; std::getline(lines, line);) {
    const json object = json::parse(line, nullptr, false);
    ASSERT_TRUE(object.is_object()) << line;
    if (object.value("level", "") == "error") {
      said = object.value("message", "")
                 .find("cannot listen on 127.0.0.1:" + std::to_string(server_->port())) !=
             std::string::npos;
    }
  }
  EXPECT_TRUE(said) << busy.out;
}

// Answers cpp-httplib makes before routing (a method it does not parse, a Range it cannot
// parse, a head that never ends) name the client, keep the X-Request-Id the client sent when the
// headers were read, and are timed: they were logged with client="" and 0 ms, and a 416 with a
// new id, which split a proxy's log from this one.
TEST_F(ServeLogTest, AnswersMadeBeforeRoutingNameTheClientKeepTheIdAndAreTimed) {
  startServer({"--read-timeout", "1"});
  const auto exchange = [&](const std::string& request) {
    const int fd = test::ConnectLoopback(server_->port());
    EXPECT_GE(fd, 0);
    EXPECT_TRUE(test::SendAll(fd, request));
    std::string answer = test::ReceiveUntil(fd, 5);
    ::close(fd);
    return answer;
  };

  const std::string made_up = exchange("FOO /livez HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(made_up.rfind("HTTP/1.1 501", 0), 0U) << made_up;
  const auto made_up_lines = LogLines(stderrFile(), "status=501");
  ASSERT_EQ(made_up_lines.size(), 1U) << ReadFile(stderrFile());
  EXPECT_NE(made_up_lines[0].find("client=127.0.0.1"), std::string::npos) << made_up_lines[0];

  const std::string bad_range = exchange(
      "GET /livez HTTP/1.1\r\nHost: x\r\nRange: bytes=zz\r\nX-Request-Id: kept-416\r\n\r\n");
  EXPECT_EQ(bad_range.rfind("HTTP/1.1 416", 0), 0U) << bad_range;
  EXPECT_NE(bad_range.find("X-Request-Id: kept-416\r\n"), std::string::npos) << bad_range;
  const auto range_lines = LogLines(stderrFile(), "id=kept-416");
  ASSERT_EQ(range_lines.size(), 1U) << ReadFile(stderrFile());
  EXPECT_NE(range_lines[0].find("status=416"), std::string::npos) << range_lines[0];
  EXPECT_NE(range_lines[0].find("client=127.0.0.1"), std::string::npos) << range_lines[0];

  // A head that stops coming: answered 408 a read timeout (1 s) after its first bytes, and
  // logged and measured as taking that long, not as the fastest request of all.
  const std::string stalled = exchange("GET /livez HTTP/1.1\r\nHost: x\r\n");
  EXPECT_EQ(stalled.rfind("HTTP/1.1 408", 0), 0U) << stalled;
  const auto stalled_lines = LogLines(stderrFile(), "status=408");
  ASSERT_EQ(stalled_lines.size(), 1U) << ReadFile(stderrFile());
  std::smatch ms;
  ASSERT_TRUE(std::regex_search(stalled_lines[0], ms, std::regex(R"( ms=([0-9.]+))")))
      << stalled_lines[0];
  EXPECT_GE(std::stod(ms[1].str()), 1000.0) << stalled_lines[0];
  const std::string metrics = client().Get("/metrics")->body;
  EXPECT_GE(
      Metric(
          metrics,
          R"(pintag_http_request_duration_seconds_sum{route="unmatched",method="other",status="408"})"),
      1.0)
      << metrics;
}

// A token that cannot be checked because the database fails is a 5xx like a handler's: logged
// under the request's id with what the client was not told. It was answered without an error
// line, so the failure could not be joined to the request.
TEST_F(ServeLogTest, ATokenCheckTheDatabaseFailsIsLoggedWithTheRequestId) {
  ASSERT_EQ(ExecuteBehindTheServer(db_path_, "DROP TABLE api_tokens;"), SQLITE_OK);
  httplib::Headers headers = admin();
  headers.emplace("X-Request-Id", "token-check-1");
  const json problem = ExpectProblem(client().Get("/api/v1/tokens", headers), 500);
  EXPECT_EQ(problem["detail"].get<std::string>().find("api_tokens"), std::string::npos)
      << "the SQL error reached the client: " << problem.dump();
  const auto lines = LogLines(stderrFile(), "token-check-1", 2);
  ASSERT_EQ(lines.size(), 2U) << ReadFile(stderrFile());
  EXPECT_NE(lines[0].find(" error error id=token-check-1"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("GET /api/v1/tokens: 500"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("checking the bearer token"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("status=500"), std::string::npos) << lines[1];
}

TEST_F(ServeLogTest, ProcessMetricsDescribeTheServerProcess) {
  const auto r = client().Get("/metrics");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  const auto value = [&](const std::string& name) {
    std::smatch m;
    const std::regex line("\n" + name + " ([0-9.e+]+)\n");
    EXPECT_TRUE(std::regex_search(r->body, m, line)) << name << " missing";
    return m.empty() ? -1.0 : std::stod(m[1].str());
  };
  EXPECT_GT(value("process_resident_memory_bytes"), 1e6);
  EXPECT_GT(value("process_virtual_memory_bytes"), value("process_resident_memory_bytes"));
  EXPECT_GT(value("process_cpu_seconds_total"), 0);
  EXPECT_GE(value("process_open_fds"), 4);  // stdin, stdout, stderr, the listening socket
  EXPECT_GT(value("process_max_fds"), value("process_open_fds"));
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const double start = value("process_start_time_seconds");
  EXPECT_LE(start, now + 2);
  EXPECT_GT(start, now - 600) << "the server started during this test";
  EXPECT_NE(r->body.find("# TYPE process_cpu_seconds_total counter"), std::string::npos);
}

TEST_F(ServeLogTest, EnvironmentVariablesConfigureServeAndFlagsWin) {
  ::setenv("PINTAG_LOG_FORMAT", "json", 1);
  ::setenv("PINTAG_MAX_BATCH", "2", 1);
  startServer();
  ::unsetenv("PINTAG_MAX_BATCH");
  auto r = client().Get("/livez", {{"X-Request-Id", "env-json"}});
  ASSERT_TRUE(r);
  const auto lines = LogLines(stderrFile(), "\"env-json\"");
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_FALSE(json::parse(lines[0], nullptr, false).is_discarded()) << lines[0];
  // PINTAG_MAX_BATCH=2: a batch of three is refused.
  const json batch = {{"pincodes", {"110001", "110001", "110001"}}};
  ExpectProblem(client().Post("/api/v1/labels", counter(), batch.dump(), "application/json"), 413);

  startServer({"--log-format", "text"});  // the flag wins over PINTAG_LOG_FORMAT=json
  ::unsetenv("PINTAG_LOG_FORMAT");
  r = client().Get("/livez", {{"X-Request-Id", "flag-text"}});
  ASSERT_TRUE(r);
  const auto text_lines = LogLines(stderrFile(), "flag-text");
  ASSERT_EQ(text_lines.size(), 1U);
  EXPECT_NE(text_lines[0].find("id=flag-text"), std::string::npos) << text_lines[0];
}

TEST(ServeHelp, NamesTheEnvironmentVariableOfEveryOption) {
  const CommandResult help = RunPintag("serve --help");
  ASSERT_EQ(help.status, 0) << help.out;
  for (const char* name : {"PINTAG_DB",
                           "PINTAG_PORT",
                           "PINTAG_BIND",
                           "PINTAG_THREADS",
                           "PINTAG_WEB",
                           "PINTAG_MAX_BODY_MB",
                           "PINTAG_MAX_PIXELS",
                           "PINTAG_MAX_PIXELS_IN_FLIGHT",
                           "PINTAG_MAX_BATCH",
                           "PINTAG_MAX_TAG_PX",
                           "PINTAG_READ_TIMEOUT",
                           "PINTAG_WRITE_TIMEOUT",
                           "PINTAG_MIN_BODY_RATE",
                           "PINTAG_DRAIN_TIMEOUT",
                           "PINTAG_ADMIN_TOKEN_OUT",
                           "PINTAG_LOG_FORMAT",
                           "PINTAG_READ_ONLY",
                           "PINTAG_FOLLOW",
                           "PINTAG_FOLLOW_TOKEN_FILE",
                           "PINTAG_FOLLOW_INTERVAL_MS",
                           "PINTAG_PRIMARY",
                           "PINTAG_SCAN_LOG",
                           "PINTAG_SNAPSHOT",
                           "PINTAG_TRUSTED_PROXY"}) {
    EXPECT_NE(help.out.find(std::string(name) + ")"), std::string::npos) << name;
  }
  // scripts/test.sh and the scratch servers clear each of them (scripts/lib.sh), so that what a
  // user exported for scripts/start.sh (PINTAG_READ_ONLY=1 failed every write test) does not
  // reach a test's server.
  std::ifstream lib_file(std::string(PINTAG_SOURCE_DIR) + "/scripts/lib.sh");
  const std::string lib((std::istreambuf_iterator<char>(lib_file)), {});
  ASSERT_FALSE(lib.empty());
  const std::regex variable(R"(Env:(PINTAG_[A-Z_]+)\))");
  int named = 0;
  for (auto it = std::sregex_iterator(help.out.begin(), help.out.end(), variable);
       it != std::sregex_iterator(); ++it, ++named) {
    const std::regex cleared("-u " + (*it)[1].str() + "[ )\n]");
    EXPECT_TRUE(std::regex_search(lib, cleared)) << (*it)[1].str() << " is not in scripts/lib.sh";
  }
  EXPECT_GE(named, 24);
  // Refused by the option's own check, before any database or port: the database's directory
  // does not exist, so a server that let the value through could not start and hang the test.
  TempDir dir;
  const std::string db = dir.file("absent/x.db");
  const CommandResult bad = RunPintag("serve --log-format xml --port 0 --db " + db);
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.out.find("--log-format"), std::string::npos) << bad.out;
  EXPECT_NE(bad.out.find("xml"), std::string::npos) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

}  // namespace
}  // namespace pintag::serve_test
