// Routing, sort plans and tokens on a real `pintag serve`.

#include <atomic>

#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

TEST_F(ServeTest, RouteAPincode) {
  json r = ExpectJson(client().Get("/api/v1/route/110001"));
  EXPECT_EQ(r["plan"], "default");
  EXPECT_EQ(r["bin"], "11");
  EXPECT_EQ(r["matched_prefix"], "11");
  EXPECT_EQ(r["fallback"], false);
  EXPECT_EQ(r["status"], "active");
  r = ExpectJson(client().Get("/api/v1/route/560001?plan=default"));
  EXPECT_EQ(r["bin"], "56");
  // Routing is by prefix: a pincode outside the registry still routes, and says so.
  r = ExpectJson(client().Get("/api/v1/route/999999"));
  EXPECT_EQ(r["status"], "unknown");
  EXPECT_EQ(r["bin"], "manual");
  EXPECT_EQ(r["fallback"], true);
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/route/110001?plan=nope"), 404)["title"],
            "Unknown Sort Plan");
  ExpectProblem(client().Get("/api/v1/route/1100"), 400);
}

TEST_F(ServeTest, SortPlansReadAndWrite) {
  json plans = ExpectJson(client().Get("/api/v1/sortplans"));
  ASSERT_EQ(plans["plans"].size(), 1U);
  EXPECT_EQ(plans["plans"][0]["name"], "default");
  EXPECT_EQ(plans["plans"][0]["fallback_bin"], "manual");
  EXPECT_EQ(plans["plans"][0]["rules"], 69);

  json plan = ExpectJson(client().Get("/api/v1/sortplans/default"));
  EXPECT_EQ(plan["rules"].size(), 69U);
  auto csv = client().Get("/api/v1/sortplans/default?format=csv");
  ASSERT_TRUE(csv);
  EXPECT_EQ(csv->status, 200);
  EXPECT_EQ(csv->get_header_value("Content-Type").rfind("text/csv", 0), 0U);
  EXPECT_EQ(csv->body.rfind("prefix,bin\n*,manual\n", 0), 0U) << csv->body.substr(0, 100);
  csv = client().Get("/api/v1/sortplans/default", {{"Accept", "text/csv"}});
  ASSERT_TRUE(csv);
  EXPECT_EQ(csv->body.rfind("prefix,bin", 0), 0U);
  // By the weights the client gives (a substring test got all three wrong).
  for (const auto& [accept, wants_csv] :
       {std::pair{"text/csv;q=0", false}, std::pair{"application/json;q=0.1, text/csv;q=0.5", true},
        std::pair{"TEXT/CSV", true}, std::pair{"text/csv;q=0.5, */*;q=0.8", false}}) {
    const auto negotiated = client().Get("/api/v1/sortplans/default", {{"Accept", accept}});
    ASSERT_TRUE(negotiated);
    EXPECT_EQ(negotiated->body.rfind("prefix,bin", 0) == 0, wants_csv) << accept;
  }
  ExpectProblem(client().Get("/api/v1/sortplans/nope"), 404);

  // PUT as CSV (admin only), then as JSON replacing it.
  const std::string north = "prefix,bin\n*,manual\n11,delhi\n110001,parliament\n56,bengaluru\n";
  ExpectProblem(client().Put("/api/v1/sortplans/hub", north, "text/csv"), 401);
  ExpectProblem(client().Put("/api/v1/sortplans/hub", counter(), north, "text/csv"), 403);
  ExpectProblem(client().Put("/api/v1/sortplans/hub", admin(), north, "text/plain"), 415);
  plan = ExpectJson(client().Put("/api/v1/sortplans/hub", admin(), north, "text/csv"), 201);
  EXPECT_EQ(plan["rules"].size(), 3U);
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/110001?plan=hub"))["bin"], "parliament");
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/110002?plan=hub"))["bin"], "delhi");
  auto label = client().Get("/api/v1/labels/110001.pdf?plan=hub", counter());
  ASSERT_TRUE(label);
  EXPECT_EQ(label->status, 200);

  const json replacement = {{"fallback_bin", "floor"},
                            {"description", "two bins"},
                            {"rules", {{{"prefix", "1"}, {"bin", "north"}}}}};
  plan = ExpectJson(
      client().Put("/api/v1/sortplans/hub", admin(), replacement.dump(), "application/json"));
  EXPECT_EQ(plan["fallback_bin"], "floor");
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/110001?plan=hub"))["bin"], "north");
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/560001?plan=hub"))["bin"], "floor");
  // Fetched as CSV and put back, the plan keeps its description (the CSV cannot hold it);
  // ?description= replaces it.
  auto hub_csv = client().Get("/api/v1/sortplans/hub?format=csv");
  ASSERT_TRUE(hub_csv);
  plan = ExpectJson(client().Put("/api/v1/sortplans/hub", admin(), hub_csv->body, "text/csv"));
  EXPECT_EQ(plan["description"], "two bins");
  EXPECT_EQ(plan["fallback_bin"], "floor");
  plan = ExpectJson(client().Put("/api/v1/sortplans/hub?description=one%20bin", admin(),
                                 hub_csv->body, "text/csv"));
  EXPECT_EQ(plan["description"], "one bin");
  // A JSON body holds its own description: ?description= beside it was dropped without a word.
  const json refused = ExpectProblem(client().Put("/api/v1/sortplans/hub?description=q", admin(),
                                                  replacement.dump(), "application/json"),
                                     400);
  EXPECT_NE(refused["detail"].get<std::string>().find("for CSV bodies"), std::string::npos);
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/sortplans/hub"))["description"], "one bin");

  // Malformed plans: no fallback row, a bad prefix, a duplicate, bad JSON.
  ExpectProblem(client().Put("/api/v1/sortplans/bad", admin(), "prefix,bin\n11,a\n", "text/csv"),
                400);
  ExpectProblem(
      client().Put("/api/v1/sortplans/bad", admin(), "prefix,bin\n*,m\n1x,a\n", "text/csv"), 400);
  ExpectProblem(
      client().Put("/api/v1/sortplans/bad", admin(), "prefix,bin\n*,m\n11,a\n11,b\n", "text/csv"),
      400);
  ExpectProblem(client().Put("/api/v1/sortplans/bad", admin(), "{", "application/json"), 400);
  // A JSON plan's faults are named like a CSV's, a misspelt field among them (it would otherwise
  // be saved without what it was meant to say).
  for (const auto& [body, named] : std::vector<std::pair<std::string, std::string>>{
           {R"({"rules": []})", "'fallback_bin' is required"},
           {R"({"fallback_bin": 7, "rules": []})", "'fallback_bin' must be a string"},
           {R"({"fallback_bin": "m", "rule": []})", "unknown field 'rule'"},
           {R"({"fallback_bin": "m", "rules": [{"prefix": "1", "bni": "a"}]})",
            "rules[0]: unknown field 'bni'"},
           {R"({"fallback_bin": "m", "rules": [{"bin": "a"}]})", "rules[0]: 'prefix' is required"},
           {R"({"fallback_bin": "m", "rules": [{"prefix": "1x", "bin": "a"}]})", "1x"}}) {
    const json problem = ExpectProblem(
        client().Put("/api/v1/sortplans/bad", admin(), body, "application/json"), 400);
    EXPECT_EQ(problem["title"], "Bad Sort Plan") << body;
    EXPECT_NE(problem["detail"].get<std::string>().find(named), std::string::npos)
        << body << " -> " << problem.dump();
  }
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/sortplans"))["plans"].size(), 2U);
}

// Two admins editing one plan: the second to save, holding the version both read, must be told
// (412) instead of silently undoing the first one's change.
TEST_F(ServeTest, SortPlanWritesAreConditionalOnTheVersionRead) {
  const std::string plan_path = "/api/v1/sortplans/hub";
  const std::string v1 = "prefix,bin\n*,manual\n11,delhi\n";
  const auto put = [&](const std::string& body, const httplib::Headers& extra,
                       const std::string& type = "text/csv") {
    httplib::Headers headers = admin();
    headers.insert(extra.begin(), extra.end());
    return client().Put(plan_path, headers, body, type);
  };
  const auto bins = [&] {
    return ExpectJson(client().Get("/api/v1/route/110001?plan=hub"))["bin"].get<std::string>();
  };

  // If-None-Match: * creates a new plan, and never replaces one.
  auto created = put(v1, {{"If-None-Match", "*"}});
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 201) << created->body;
  const std::string etag = created->get_header_value("ETag");
  ASSERT_EQ(etag.size(), 34U) << etag;  // "…32 hex digits…", strong (no W/)
  EXPECT_EQ(etag.front(), '"');
  EXPECT_EQ(ExpectProblem(put("prefix,bin\n*,other\n", {{"If-None-Match", "*"}}), 412)["title"],
            "Precondition Failed");
  EXPECT_EQ(bins(), "delhi");

  // GET sends the same version; the CSV form its own tag of it.
  auto got = client().Get(plan_path);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->get_header_value("ETag"), etag);
  auto got_csv = client().Get(plan_path + "?format=csv");
  ASSERT_TRUE(got_csv);
  const std::string csv_etag = got_csv->get_header_value("ETag");
  EXPECT_EQ(csv_etag, etag.substr(0, 33) + "-csv\"");
  // A GET whose If-None-Match names the representation's version (weakly) is 304 with its tag and
  // no body; the other representation's tag, or an older one, is not its version.
  for (const auto& [path, tag] :
       {std::pair{plan_path, etag}, std::pair{plan_path, "W/" + etag},
        std::pair{plan_path + "?format=csv", csv_etag}, std::pair{plan_path, std::string("*")}}) {
    const auto held = client().Get(path, {{"If-None-Match", tag}});
    ASSERT_TRUE(held);
    EXPECT_EQ(held->status, 304) << path << " " << tag;
    EXPECT_TRUE(held->body.empty());
    EXPECT_EQ(held->get_header_value("ETag"), path == plan_path ? etag : csv_etag);
  }
  for (const auto& [path, tag] :
       {std::pair{plan_path, csv_etag}, std::pair{plan_path + "?format=csv", etag},
        std::pair{plan_path, std::string("\"older\", \"other\"")}}) {
    const auto sent = client().Get(path, {{"If-None-Match", tag}});
    ASSERT_TRUE(sent);
    EXPECT_EQ(sent->status, 200) << path << " " << tag;
    EXPECT_FALSE(sent->body.empty());
  }
  // A malformed one (an unquoted version) is ignored on a GET, as before the route read it.
  const auto unquoted = client().Get(plan_path, {{"If-None-Match", etag.substr(1, 32)}});
  ASSERT_TRUE(unquoted);
  EXPECT_EQ(unquoted->status, 200) << unquoted->body;

  // A tag that is not the plan's, or a plan that is not there: 412, nothing written.
  const json stale = ExpectProblem(put("prefix,bin\n*,other\n", {{"If-Match", "\"nope\""}}), 412);
  EXPECT_EQ(stale["title"], "Precondition Failed");
  EXPECT_NE(stale["detail"].get<std::string>().find(etag.substr(1, 32)), std::string::npos)
      << stale.dump();
  EXPECT_EQ(bins(), "delhi");
  ExpectJson(put(v1, {{"If-Match", "*"}}));  // met by any plan there; the same plan, same tag
  EXPECT_EQ(client().Get(plan_path)->get_header_value("ETag"), etag);
  auto absent = client().Put(
      "/api/v1/sortplans/absent",
      httplib::Headers{{"Authorization", "Bearer " + admin_token_}, {"If-Match", etag}}, v1,
      "text/csv");
  ExpectProblem(absent, 412);
  ExpectProblem(client().Get("/api/v1/sortplans/absent"), 404);
  // A weak tag never matches If-Match (strong comparison); a malformed header is refused.
  ExpectProblem(put(v1, {{"If-Match", "W/" + etag}}), 412);
  EXPECT_EQ(ExpectProblem(put(v1, {{"If-Match", "nope"}}), 400)["detail"].get<std::string>().find(
                "If-Match"),
            0U);

  // The current tag, in either form, is met once: the answer carries the new version, and the
  // old tag is then refused.
  std::string current = client().Get(plan_path)->get_header_value("ETag");
  auto saved =
      put("prefix,bin\n*,manual\n11,north\n", {{"If-Match", current.substr(0, 33) + "-csv\""}});
  ASSERT_TRUE(saved);
  ASSERT_EQ(saved->status, 200) << saved->body;
  EXPECT_NE(saved->get_header_value("ETag"), current);
  EXPECT_EQ(saved->get_header_value("ETag"), client().Get(plan_path)->get_header_value("ETag"));
  EXPECT_EQ(bins(), "north");
  ExpectProblem(put("prefix,bin\n*,manual\n11,lost\n", {{"If-Match", current}}), 412);
  EXPECT_EQ(bins(), "north");

  // Several writers holding the same version at once: exactly one wins.
  current = client().Get(plan_path)->get_header_value("ETag");
  std::atomic<int> next{0}, refused{0};
  const int won = CallsRightFromConcurrentClients(server_->port(), 6, 1, [&](httplib::Client& c) {
    const std::string bin = "writer" + std::to_string(next++);
    auto r = c.Put(plan_path, {{"Authorization", "Bearer " + admin_token_}, {"If-Match", current}},
                   "prefix,bin\n*,manual\n11," + bin + "\n", "text/csv");
    if (r && r->status == 412) ++refused;
    return r && r->status == 200;
  });
  EXPECT_EQ(won, 1);
  EXPECT_EQ(refused, 5);

  // Without either header a PUT overwrites, as it always did.
  ExpectJson(put("prefix,bin\n*,manual\n11,last\n", {}));
  EXPECT_EQ(bins(), "last");
}

// A plan a hub no longer uses is deleted by an admin, answered as it was (so that a mistaken
// delete can be put back), and conditionally on the version read as a PUT is; the default plan,
// which labels and scans naming no plan use, is never deleted.
TEST_F(ServeTest, SortPlansAreDeletedByAnAdminAndAnsweredAsTheyWere) {
  const std::string plan_path = "/api/v1/sortplans/hub";
  const std::string csv = "prefix,bin\n*,manual\n11,delhi\n56,bengaluru\n";
  const auto del = [&](const std::string& path, const httplib::Headers& extra = {}) {
    httplib::Headers headers = admin();
    headers.insert(extra.begin(), extra.end());
    return client().Delete(path, headers);
  };
  auto created = client().Put(plan_path + "?description=north%20hub", admin(), csv, "text/csv");
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 201) << created->body;
  const std::string etag = created->get_header_value("ETag");

  // Only an admin deletes.
  ExpectProblem(client().Delete(plan_path), 401);
  ExpectProblem(client().Delete(plan_path, counter()), 403);
  ExpectProblem(client().Delete(plan_path, scanner()), 403);

  // A tag that is not the plan's: 412, and the plan still routes.
  const json stale = ExpectProblem(del(plan_path, {{"If-Match", "\"nope\""}}), 412);
  EXPECT_NE(stale["detail"].get<std::string>().find(etag.substr(1, 32)), std::string::npos)
      << stale.dump();
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/560001?plan=hub"))["bin"], "bengaluru");

  // The tag read: deleted, answered as it was with that tag.
  auto deleted = del(plan_path, {{"If-Match", etag}});
  ASSERT_TRUE(deleted);
  ASSERT_EQ(deleted->status, 200) << deleted->body;
  EXPECT_EQ(deleted->get_header_value("ETag"), etag);
  const json was = json::parse(deleted->body);
  EXPECT_EQ(was["name"], "hub");
  EXPECT_EQ(was["fallback_bin"], "manual");
  EXPECT_EQ(was["description"], "north hub");
  EXPECT_EQ(was["rules"].size(), 2U);

  // Gone: not listed, not read, not routed by, not on a label; a second delete is 404.
  ExpectProblem(client().Get(plan_path), 404);
  ExpectProblem(client().Get("/api/v1/route/560001?plan=hub"), 404);
  ExpectProblem(client().Get("/api/v1/labels/560001.png?plan=hub", counter()), 404);
  for (const json& plan : ExpectJson(client().Get("/api/v1/sortplans"))["plans"]) {
    EXPECT_NE(plan["name"], "hub");
  }
  // The second delete's 404 has the title every route gives an unknown plan ("Not Found" before).
  EXPECT_EQ(ExpectProblem(del(plan_path), 404)["title"], "Unknown Sort Plan");
  EXPECT_EQ(ExpectProblem(client().Get(plan_path), 404)["title"], "Unknown Sort Plan");
  ExpectProblem(del(plan_path, {{"If-Match", "*"}}), 412);

  // What the delete answered puts the plan back as it was.
  auto restored = client().Put(plan_path, admin(), deleted->body, "application/json");
  ASSERT_TRUE(restored);
  EXPECT_EQ(restored->status, 201) << restored->body;
  EXPECT_EQ(restored->get_header_value("ETag"), etag);
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/560001?plan=hub"))["bin"], "bengaluru");

  // Without If-Match a delete takes the plan whatever it is now.
  ExpectJson(del(plan_path));
  ExpectProblem(client().Get(plan_path), 404);

  // The default plan stays, with or without its tag.
  const std::string default_etag =
      client().Get("/api/v1/sortplans/default")->get_header_value("ETag");
  const json kept = ExpectProblem(del("/api/v1/sortplans/default"), 409);
  EXPECT_NE(kept["detail"].get<std::string>().find("default"), std::string::npos) << kept.dump();
  ExpectProblem(del("/api/v1/sortplans/default", {{"If-Match", default_etag}}), 409);
  EXPECT_EQ(client().Get("/api/v1/sortplans/default")->get_header_value("ETag"), default_etag);
}

// A rule no pincode can match, or a prefix given twice, is refused naming the line (or rule) so a
// long CSV can be put right; nothing is saved.
TEST_F(ServeTest, SortPlanFaultsAreNamedByLine) {
  const auto refused = [&](const std::string& body, const std::string& type,
                           const std::string& says) {
    const json problem =
        ExpectProblem(client().Put("/api/v1/sortplans/bad", admin(), body, type), 400);
    EXPECT_EQ(problem["title"], "Bad Sort Plan");
    EXPECT_NE(problem["detail"].get<std::string>().find(says), std::string::npos)
        << body << " -> " << problem.dump();
  };
  refused("prefix,bin\n*,m\n11,a\n0,zero\n", "text/csv", "line 4: rule prefix '0' starts with 0");
  refused("prefix,bin\n*,m\n012345,z\n", "text/csv", "line 3: rule prefix '012345' starts with 0");
  refused(
      R"({"fallback_bin": "m", "rules": [{"prefix": "1", "bin": "a"}, {"prefix": "04", "bin": "b"}]})",
      "application/json", "rules[1]: rule prefix '04' starts with 0");
  refused("prefix,bin\n*,m\n11,a\n56,b\n11,c\n", "text/csv",
          "line 5: prefix 11 appears twice (first on line 3)");
  refused(
      R"({"fallback_bin": "m", "rules": [{"prefix": "11", "bin": "a"}, {"prefix": "11", "bin": "b"}]})",
      "application/json", "rules[1]: prefix 11 appears twice (first at rules[0])");
  refused("prefix,bin\n*,m\n11,\"\u200b\"\n", "text/csv", "line 3: bin for prefix 11 is blank");
  ExpectProblem(client().Get("/api/v1/sortplans/bad"), 404);
}

// "café" with é as one character and as e + U+0301 read alike: a second plan or bin written the
// other way is refused naming the first, and a plan asked for the other way is named.
TEST_F(ServeTest, PlanNamesAndBinsThatReadAlikeAreNotTwo) {
  const std::string composed = "caf\u00e9";
  const std::string decomposed = "cafe\u0301";
  const std::string plan_csv = "prefix,bin\n*,manual\n11," + composed + "\n";
  ExpectJson(client().Put("/api/v1/sortplans/hub-" + composed, admin(), plan_csv, "text/csv"), 201);
  const json twin = ExpectProblem(
      client().Put("/api/v1/sortplans/hub-" + decomposed, admin(), plan_csv, "text/csv"), 409);
  EXPECT_EQ(twin["title"], "Sort Plan Reads Alike");
  EXPECT_NE(twin["detail"].get<std::string>().find("the plan 'hub-" + composed +
                                                   "' (U+00E9) reads the same"),
            std::string::npos)
      << twin.dump();
  const json asked =
      ExpectProblem(client().Get("/api/v1/route/110001?plan=" +
                                 httplib::detail::encode_query_param("hub-" + decomposed)),
                    404);
  EXPECT_EQ(asked["title"], "Unknown Sort Plan");
  EXPECT_NE(
      asked["detail"].get<std::string>().find("'hub-" + composed + "' (U+00E9) reads the same"),
      std::string::npos)
      << asked.dump();
  const json bins = ExpectProblem(
      client().Put("/api/v1/sortplans/hub-" + composed, admin(),
                   "prefix,bin\n*,manual\n11," + composed + "\n56," + decomposed + "\n",
                   "text/csv"),
      400);
  EXPECT_EQ(bins["title"], "Bad Sort Plan");
  EXPECT_NE(bins["detail"].get<std::string>().find("bin for prefix 56"), std::string::npos)
      << bins.dump();
  // The plan as first written still routes.
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/110001?plan=" +
                                    httplib::detail::encode_query_param("hub-" + composed)))["bin"],
            composed);
}

// A plan has at most 100,000 rules: one over is refused naming the limit, without saving.
TEST_F(ServeTest, SortPlanRuleLimit) {
  std::string csv = "prefix,bin\n*,manual\n";
  for (int prefix = 100000; prefix < 200000; ++prefix) {
    csv += std::to_string(prefix) + ",b" + std::to_string(prefix % 100) + "\n";
  }
  ExpectJson(client().Put("/api/v1/sortplans/big", admin(), csv, "text/csv"), 201);
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/123456?plan=big"))["bin"], "b56");
  const json over = ExpectProblem(
      client().Put("/api/v1/sortplans/big", admin(), csv + "200000,over\n", "text/csv"), 413);
  EXPECT_NE(
      over["detail"].get<std::string>().find("line 100003: a sort plan has at most 100000 rules"),
      std::string::npos)
      << over.dump();
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/route/200000?plan=big"))["bin"], "manual");
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/sortplans"))["plans"][0]["name"], "big");
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/sortplans"))["plans"][0]["rules"], 100000);
}

TEST_F(ServeTest, TokensCreateListRevoke) {
  ExpectProblem(client().Get("/api/v1/tokens"), 401);
  ExpectProblem(client().Get("/api/v1/tokens", counter()), 403);
  ExpectProblem(
      client().Post("/api/v1/tokens", scanner(), R"({"role": "admin"})", "application/json"), 403);
  const json created =
      ExpectJson(client().Post("/api/v1/tokens", admin(),
                               R"({"role": "scanner", "label": "handheld 7"})", "application/json"),
                 201);
  const std::string secret = created["secret"];
  EXPECT_EQ(secret.rfind("pt_", 0), 0U);
  EXPECT_EQ(created["role"], "scanner");
  EXPECT_EQ(created["label"], "handheld 7");
  const int id = created["id"];

  // The new token works at once; the list never shows a secret.
  const json detect_free = ExpectJson(client().Get("/api/v1/tokens", admin()));
  EXPECT_EQ(detect_free["tokens"].size(), 4U);
  EXPECT_EQ(detect_free.dump().find(secret), std::string::npos);
  EXPECT_EQ(detect_free.dump().find("secret"), std::string::npos);
  auto r = client().Post("/api/v1/detect", Auth(secret), std::string(10, 'x'), "image/jpeg");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 415);  // admitted (the bytes are not an image)

  // Revoke by DELETE; the token is refused from then on.
  const json revoked = ExpectJson(client().Delete("/api/v1/tokens/" + std::to_string(id), admin()));
  EXPECT_FALSE(revoked["revoked_at"].is_null());
  ExpectProblem(client().Post("/api/v1/detect", Auth(secret), std::string(10, 'x'), "image/jpeg"),
                401);
  // Revoke by POST …/revoke: the counter token stops working.
  ExpectJson(client().Post("/api/v1/tokens/" + std::to_string(counter_token_id_) + "/revoke",
                           admin(), "", "text/plain"));
  ExpectProblem(client().Get("/api/v1/tags/110001.png", counter()), 401);

  ExpectProblem(client().Delete("/api/v1/tokens/999", admin()), 404);
  ExpectProblem(client().Delete("/api/v1/tokens/abc", admin()), 400);
  ExpectProblem(client().Post("/api/v1/tokens", admin(), R"({"role": "root"})", "application/json"),
                400);
  ExpectProblem(client().Post("/api/v1/tokens", admin(), R"(["admin"])", "application/json"), 400);
  // A misspelt field is refused, not dropped (the token would have no label), and none is made.
  const std::size_t tokens = ExpectJson(client().Get("/api/v1/tokens", admin()))["tokens"].size();
  const json misspelt =
      ExpectProblem(client().Post("/api/v1/tokens", admin(), R"({"role": "scanner", "lable": "x"})",
                                  "application/json"),
                    400);
  EXPECT_NE(misspelt["detail"].get<std::string>().find("unknown field 'lable'"), std::string::npos)
      << misspelt.dump();
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/tokens", admin()))["tokens"].size(), tokens);

  // The last active admin token is not revoked through the API: nobody could administer the
  // server through it again (a review revoked it and locked the API for everyone).
  int admin_id = 0;
  const json listed = ExpectJson(client().Get("/api/v1/tokens", admin()));
  for (const json& token : listed["tokens"]) {
    if (token["role"] == "admin" && token["revoked_at"].is_null()) admin_id = token["id"];
  }
  ASSERT_GT(admin_id, 0);
  const std::string admin_path = "/api/v1/tokens/" + std::to_string(admin_id);
  const json last = ExpectProblem(client().Delete(admin_path, admin()), 409);
  EXPECT_EQ(last["title"], "Last Admin Token");
  EXPECT_NE(last["detail"].get<std::string>().find("create another admin token before revoking"),
            std::string::npos)
      << last;
  ExpectJson(client().Get("/api/v1/tokens", admin()));  // still works
  // With a second admin it may go; then the second is the last.
  const json second = ExpectJson(
      client().Post("/api/v1/tokens", admin(), R"({"role": "admin"})", "application/json"), 201);
  const std::string second_secret = second["secret"];
  ExpectJson(client().Delete(admin_path, Auth(second_secret)));
  ExpectProblem(client().Get("/api/v1/tokens", admin()), 401);
  const std::string second_path = "/api/v1/tokens/" + std::to_string(second["id"].get<int>());
  EXPECT_EQ(ExpectProblem(client().Delete(second_path, Auth(second_secret)), 409)["title"],
            "Last Admin Token");
  // Revoking a revoked admin token stays a no-op, not a conflict.
  ExpectJson(client().Delete(admin_path, Auth(second_secret)));
}

}  // namespace
}  // namespace pintag::serve_test
