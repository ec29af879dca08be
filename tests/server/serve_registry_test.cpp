// Registry routes of a real `pintag serve`: lookups, search, keys, adding and retiring.

#include "pintag/db/database.hpp"
#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

TEST_F(ServeTest, PincodeLookupLooksLikeThePostalApi) {
  const json p = ExpectJson(client().Get("/api/v1/pincodes/110001"));
  EXPECT_EQ(p["pincode"], "110001");
  EXPECT_EQ(p["key"], 11684);  // the seed's key table (DESIGN.md §2 probing)
  EXPECT_EQ(p["status"], "active");
  EXPECT_EQ(p["district"], "Central Delhi");
  EXPECT_EQ(p["state"], "Delhi");
  EXPECT_EQ(p["circle"], "Delhi");
  EXPECT_EQ(p["region"], "Delhi");
  EXPECT_EQ(p["division"], "New Delhi Central");
  ASSERT_TRUE(p["offices"].is_array());
  EXPECT_EQ(p["offices"].size(), p["office_count"].get<std::size_t>());
  EXPECT_GT(p["offices"].size(), 10U);
  bool connaught = false;
  for (const json& office : p["offices"]) {
    for (const char* field : {"name", "branch_type", "delivery", "circle", "region", "division",
                              "district", "state", "pincode", "country"}) {
      EXPECT_TRUE(office.contains(field)) << field;
    }
    EXPECT_EQ(office["pincode"], "110001");
    connaught = connaught || office["name"] == "Connaught Place";
  }
  EXPECT_TRUE(connaught);
}

TEST_F(ServeTest, PincodeLookupErrors) {
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/pincodes/999999"), 404)["title"],
            "Unknown Pincode");
  for (const char* bad :
       {"/api/v1/pincodes/11001", "/api/v1/pincodes/1100010", "/api/v1/pincodes/011001",
        "/api/v1/pincodes/11000x", "/api/v1/pincodes/%20110001"}) {
    EXPECT_EQ(ExpectProblem(client().Get(bad), 400)["title"], "Malformed Pincode") << bad;
  }
  ExpectProblem(client().Delete("/api/v1/pincodes/110001", admin()), 405);
}

TEST_F(ServeTest, SearchByOfficeDistrictAndState) {
  json page = ExpectJson(client().Get("/api/v1/pincodes?q=connaught"));
  ASSERT_GE(page["total"].get<int>(), 1);
  EXPECT_EQ(page["results"][0]["pincode"], "110001");
  EXPECT_EQ(page["results"][0]["office"]["name"], "Connaught Place");
  EXPECT_EQ(page["results"][0]["key"], 11684);

  page = ExpectJson(client().Get("/api/v1/pincodes?district=Central%20Delhi&limit=5&offset=2"));
  EXPECT_GT(page["total"].get<int>(), 5);
  EXPECT_EQ(page["limit"], 5);
  EXPECT_EQ(page["offset"], 2);
  EXPECT_EQ(page["results"].size(), 5U);
  for (const json& hit : page["results"]) EXPECT_EQ(hit["office"]["district"], "Central Delhi");

  page = ExpectJson(client().Get("/api/v1/pincodes?state=Delhi&q=Par&limit=500"));
  for (const json& hit : page["results"]) EXPECT_EQ(hit["office"]["state"], "Delhi");

  ExpectProblem(client().Get("/api/v1/pincodes"), 400);
  ExpectProblem(client().Get("/api/v1/pincodes?q=a&limit=0"), 400);
  ExpectProblem(client().Get("/api/v1/pincodes?q=a&limit=501"), 400);
  ExpectProblem(client().Get("/api/v1/pincodes?q=a&offset=-1"), 400);
  ExpectProblem(client().Get("/api/v1/pincodes?q=a&limit=ten"), 400);
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/pincodes?q=%27%3B%20DROP%20TABLE"))["total"], 0);
}

TEST_F(ServeTest, KeyLookup) {
  const json p = ExpectJson(client().Get("/api/v1/keys/11684"));
  EXPECT_EQ(p["pincode"], "110001");
  EXPECT_EQ(p["key"], 11684);
  for (const char* bad :
       {"/api/v1/keys/32768", "/api/v1/keys/-1", "/api/v1/keys/abc", "/api/v1/keys/1e3"}) {
    EXPECT_EQ(ExpectProblem(client().Get(bad), 400)["title"], "Malformed Key") << bad;
  }
  // 19,159 of 32,768 keys are taken by the seed: find a free one through the API's own answers.
  const int free_key = freeKey();
  ASSERT_GE(free_key, 0);
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/keys/" + std::to_string(free_key)), 404)["title"],
            "Unknown Key");
}

TEST_F(ServeTest, AddAndRetireNeedAdmin) {
  const std::string body =
      R"({"pincode": "999001", "offices": [{"name": "Test Nagar", "district": "Testpur",
          "state": "Test State", "circle": "Test", "region": "T", "division": "TD",
          "branch_type": "HO"}]})";
  ExpectProblem(client().Post("/api/v1/pincodes", body, "application/json"), 401);
  ExpectProblem(client().Post("/api/v1/pincodes", Auth("pt_1_wrong"), body, "application/json"),
                401);
  ExpectProblem(client().Post("/api/v1/pincodes", counter(), body, "application/json"), 403);
  ExpectProblem(client().Post("/api/v1/pincodes", scanner(), body, "application/json"), 403);
  ExpectProblem(client().Post("/api/v1/pincodes", admin(), body, "text/plain"), 415);

  const json added =
      ExpectJson(client().Post("/api/v1/pincodes", admin(), body, "application/json"), 201);
  EXPECT_EQ(added["pincode"], "999001");
  ASSERT_TRUE(added["key"].is_number_integer());
  const int key = added["key"];
  EXPECT_EQ(added["office"], "Test Nagar");
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/keys/" + std::to_string(key)))["pincode"], "999001");
  EXPECT_EQ(ExpectProblem(client().Post("/api/v1/pincodes", admin(), body, "application/json"),
                          409)["title"],
            "Pincode Exists");
  ExpectProblem(
      client().Post("/api/v1/pincodes", admin(), R"({"pincode": "99900"})", "application/json"),
      400);
  ExpectProblem(client().Post("/api/v1/pincodes", admin(), "{not json", "application/json"), 400);
  ExpectProblem(client().Post("/api/v1/pincodes", admin(),
                              R"({"pincode": "999002", "offices": [{"name": "No district"}]})",
                              "application/json"),
                400);

  ExpectProblem(client().Post("/api/v1/pincodes/999001/retire", counter(), "", "text/plain"), 403);
  // A body here was dropped unread and the pincode retired (200): it is refused, and nothing done.
  for (const auto& [sent, type] :
       {std::pair{"junk", "text/plain"}, std::pair{R"({"reason": "moved"})", "application/json"}}) {
    EXPECT_NE(ExpectProblem(client().Post("/api/v1/pincodes/999001/retire", admin(), sent, type),
                            400)["detail"]
                  .get<std::string>()
                  .find("takes no body"),
              std::string::npos);
  }
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/pincodes/999001"))["status"], "active");
  const json retired =
      ExpectJson(client().Post("/api/v1/pincodes/999001/retire", admin(), "", "text/plain"));
  EXPECT_EQ(retired["status"], "retired");
  EXPECT_EQ(retired["key"], key);  // a retired pincode keeps its key
  EXPECT_FALSE(retired["retired_at"].is_null());
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/keys/" + std::to_string(key)))["status"], "retired");
  ExpectProblem(client().Post("/api/v1/pincodes/999009/retire", admin(), "", "text/plain"), 404);
  ExpectProblem(client().Post("/api/v1/pincodes/99900/retire", admin(), "", "text/plain"), 400);
}

// What an admin posts is kept whole or refused whole: nothing typed is dropped on the way in.
TEST_F(ServeTest, AddKeepsEveryOfficeFieldOrRefusesSayingWhichIsWrong) {
  const std::string office = R"("name": "Map Nagar", "district": "Testpur", "state": "Test State",
      "circle": "Test", "region": "T", "division": "TD", "branch_type": "SO", "taluk": "Testpur",
      "latitude": 28.6139, "longitude": 77.209)";
  ExpectJson(
      client().Post("/api/v1/pincodes", admin(),
                    R"({"pincode": "999011", "offices": [{)" + office + "}]}", "application/json"),
      201);
  const json read = ExpectJson(client().Get("/api/v1/pincodes/999011"));
  ASSERT_EQ(read["offices"].size(), 1U);
  const json& kept = read["offices"][0];
  EXPECT_DOUBLE_EQ(kept["latitude"].get<double>(), 28.6139);
  EXPECT_DOUBLE_EQ(kept["longitude"].get<double>(), 77.209);
  EXPECT_EQ(kept["taluk"], "Testpur");
  EXPECT_EQ(kept["branch_type"], "SO");

  // Types and unknowns as an import reads them (docs/REGISTRY.md): "H.O" is a head office, the one
  // a label prints; "NA" in an optional field is no value.
  const json typed = ExpectJson(client().Post("/api/v1/pincodes", admin(),
                                              R"({"pincode": "999014", "offices": [
                      {"name": "Branch", "branch_type": "B.O", "district": "D", "state": "S",
                       "circle": "C", "region": "R", "division": "V", "taluk": "NA"},
                      {"name": "Head", "branch_type": " h.o. ", "district": "D", "state": "S",
                       "circle": "C", "region": "R", "division": "V", "delivery": "N/A"}]})",
                                              "application/json"),
                                201);
  EXPECT_EQ(typed["office"], "Head") << typed.dump();
  for (const json& stored : typed["offices"]) {
    EXPECT_EQ(stored["branch_type"], stored["name"] == "Head" ? "HO" : "BO") << stored.dump();
    EXPECT_TRUE(stored["taluk"].is_null()) << stored.dump();
    EXPECT_TRUE(stored["delivery"].is_null()) << stored.dump();
  }

  // An office read back can be posted again as it is (country and its own pincode included).
  json again = json::parse(R"({"pincode": "999011"})");
  again["offices"] = read["offices"];
  EXPECT_EQ(
      ExpectProblem(client().Post("/api/v1/pincodes", admin(), again.dump(), "application/json"),
                    409)["title"],
      "Pincode Exists");  // refused for the pincode, not for the office's fields

  // The office with some fields changed, as a JSON object (each key once).
  const auto office_with = [&](const json& changes) {
    json changed = json::parse("{" + office + "}");
    for (const auto& [field, value] : changes.items()) changed[field] = value;
    return changed.dump();
  };
  const auto refused = [&](const std::string& body, const std::string& says) {
    const json problem =
        ExpectProblem(client().Post("/api/v1/pincodes", admin(), body, "application/json"), 400);
    EXPECT_NE(problem.value("detail", "").find(says), std::string::npos) << body << "\n"
                                                                         << problem.dump();
    // Nothing was added.
    ExpectProblem(client().Get("/api/v1/pincodes/999012"), 404);
  };
  refused(R"({"pincode": "999012", "offices": [{"name": "Only A Name"}]})",
          "office 1 needs a non-empty district, state, circle, region, division");
  refused(R"({"pincode": "999012", "offices": [{)" + office + R"(, "distrct": "Typo"}]})",
          "office 1: unknown field 'distrct'");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"name", "   "}}) + "]}",
          "needs a non-empty name");
  // Invisible text is blank too: a zero-width space for a name, a no-break space for a district.
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"name", "\u200b"}}) + "]}",
          "needs a non-empty name");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"district", "\u00a0"}}) + "]}",
          "needs a non-empty district");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"state", "\ufeff\u3000"}}) + "]}",
          "needs a non-empty state");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"latitude", "north"}}) + "]}",
          "'latitude' must be a number");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"latitude", 91}}) + "]}",
          "latitude must be -90 to 90");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"longitude", 500}}) + "]}",
          "office 1: longitude must be -180 to 180");
  // India Post's "unknown" in a required field would print on labels as a place, as an import
  // refuses it; the office is named.
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"name", "Other"}}) + "," +
              office_with({{"district", " n/a"}}) + "]}",
          "office 2: district is ' n/a', which means unknown; it is required");
  // Every unknown field and every missing one in one answer.
  const json everything_wrong = ExpectProblem(
      client().Post("/api/v1/pincodes", admin(),
                    R"({"pincode": "999012", "offices": [{"name": "", "state": "S", "foo": 1,
                        "bar": 2}]})",
                    "application/json"),
      400);
  EXPECT_NE(everything_wrong.value("detail", "")
                .find("office 1: unknown fields 'bar', 'foo'; office 1 needs a non-empty name, "
                      "district, circle, region, division"),
            std::string::npos)
      << everything_wrong.dump();
  // Named ten at most, each cut short: a body of junk keys is not echoed back whole.
  json many = json::parse("{" + office + "}");
  for (int i = 0; i < 500; ++i) many["junk" + std::string(100, 'x') + std::to_string(i)] = 1;
  const json capped = ExpectProblem(
      client().Post("/api/v1/pincodes", admin(),
                    json{{"pincode", "999012"}, {"offices", {many}}}.dump(), "application/json"),
      400);
  EXPECT_NE(capped.value("detail", "").find(" and 490 more"), std::string::npos) << capped.dump();
  EXPECT_LT(capped.value("detail", "").size(), 1000U);
  refused(R"({"pincode": "999012", "key": 5})", "unknown field 'key'");
  refused(R"({"pincode": "999012", "offices": [{)" + office + R"(, "pincode": "999013"}]})",
          "is not the pincode being added");
  // Two offices under one name would be stored as one mixing both: refused, naming it.
  const std::string alpha_a = R"({"name": "Alpha", "district": "North", "state": "State A",
      "circle": "C", "region": "R", "division": "D"})";
  const std::string alpha_b = R"({"name": "Alpha", "district": "South", "state": "State B",
      "circle": "C", "region": "R", "division": "D"})";
  refused(R"({"pincode": "999012", "offices": [)" + alpha_a + "," + alpha_b + "]}",
          "offices 1 and 2 are both named 'Alpha'");
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"name", " Beta"}}) + "," +
              office_with({{"name", "Beta"}}) + "]}",
          "both named 'Beta'");
  // A security review stored 'Janpath', 'Janpath' + U+200B and 'Janpath' + U+00A0 as three
  // offices of one pincode, and the zero-width one was printed as its head office.
  for (const std::string& name : {std::string("Janpath\u200b"), std::string("Jan\u200bpath"),
                                  std::string("Janpath\u00a0"), std::string("\u2060Janpath")}) {
    refused(R"({"pincode": "999012", "offices": [)" + office_with({{"name", name}}) + "]}",
            "office 1: office name");
  }
  // The same letters in two Unicode forms (é as one code point, or e and U+0301).
  refused(R"({"pincode": "999012", "offices": [)" + office_with({{"name", "Caf\u00e9"}}) + "," +
              office_with({{"name", "Cafe\u0301"}}) + "]}",
          "offices 1 and 2 are named alike");
  EXPECT_EQ(client().Get("/api/v1/pincodes/999012")->status, 404);
  // Spaces between words, and the joiners Indic words are written with, are names as they read.
  const auto added = client().Post(
      "/api/v1/pincodes", admin(),
      R"({"pincode": "999012", "offices": [)" + office_with({{"name", "Janpath Road"}}) + "," +
          office_with({{"name", "\u0926\u093f\u200d\u0932\u094d\u0932\u0940"}}) + "]}",
      "application/json");
  ASSERT_TRUE(added);
  EXPECT_EQ(added->status, 201) << added->body;
}

// With every key taken, adding a pincode is 507 titled as docs/API.md says: the reason phrase.
TEST_F(ServeTest, NoKeyLeftIsInsufficientStorage) {
  {
    // Every free key given to a pincode from 950000 up that the registry lacks, in one go.
    auto opened = db::OpenDatabase(db_path_, {.create = false});
    ASSERT_TRUE(opened) << opened.error().message;
    db::Connection& connection = opened.value().connection;
    connection.execute(R"sql(
      CREATE TEMP TABLE free_keys AS
        WITH RECURSIVE k(v) AS (SELECT 0 UNION ALL SELECT v + 1 FROM k WHERE v < 32767)
        SELECT v, row_number() OVER (ORDER BY v) AS n FROM k
        WHERE v NOT IN (SELECT tag_key FROM tag_keys);
      CREATE TEMP TABLE free_pins AS
        WITH RECURSIVE p(v) AS (SELECT 950000 UNION ALL SELECT v + 1 FROM p WHERE v < 999990)
        SELECT v, row_number() OVER (ORDER BY v) AS n FROM p
        WHERE v NOT IN (SELECT pincode FROM pincodes);
      BEGIN;
      INSERT INTO pincodes (pincode, status, added_at, source)
        SELECT free_pins.v, 'active', 'test', 'test' FROM free_keys JOIN free_pins USING (n);
      INSERT INTO tag_keys (pincode, tag_key, allocated_at)
        SELECT free_pins.v, free_keys.v, 'test' FROM free_keys JOIN free_pins USING (n);
      COMMIT;
    )sql");
    ASSERT_EQ(connection.queryInt64("SELECT count(*) FROM tag_keys"), 32768);
  }
  const json full = ExpectProblem(
      client().Post("/api/v1/pincodes", admin(),
                    R"({"pincode": "999999", "offices": [{"name": "Last", "district": "D",
                        "state": "S", "circle": "C", "region": "R", "division": "V"}]})",
                    "application/json"),
      507);
  EXPECT_EQ(full["title"], "Insufficient Storage");
  ExpectProblem(client().Get("/api/v1/pincodes/999999"), 404);
}

// A key twice in one object would act on one of two values the client sent (the parser keeps the
// last): every JSON body route refuses it, naming the key, and does nothing.
TEST_F(ServeTest, JsonBodyWithAKeyTwiceIsRefusedNamingIt) {
  const auto refused = [&](const httplib::Result& r, const std::string& key) {
    const json problem = ExpectProblem(r, 400);
    EXPECT_EQ(problem["title"], "Malformed JSON");
    EXPECT_NE(problem["detail"].get<std::string>().find("'" + key + "' appears twice"),
              std::string::npos)
        << problem.dump();
  };
  refused(client().Post("/api/v1/pincodes", admin(),
                        R"({"pincode": "999003", "pincode": "999004"})", "application/json"),
          "pincode");
  ExpectProblem(client().Get("/api/v1/pincodes/999003"), 404);
  ExpectProblem(client().Get("/api/v1/pincodes/999004"), 404);
  // In a nested object too.
  refused(client().Post("/api/v1/pincodes", admin(),
                        R"({"pincode": "999003", "offices": [{"name": "A", "name": "B",
                            "district": "D", "state": "S", "circle": "C", "region": "R",
                            "division": "V"}]})",
                        "application/json"),
          "name");
  ExpectProblem(client().Get("/api/v1/pincodes/999003"), 404);
  refused(client().Put("/api/v1/sortplans/twice", admin(),
                       R"({"fallback_bin": "a", "fallback_bin": "b", "rules": []})",
                       "application/json"),
          "fallback_bin");
  ExpectProblem(client().Get("/api/v1/sortplans/twice"), 404);
  refused(client().Post("/api/v1/tokens", admin(), R"({"role": "scanner", "role": "admin"})",
                        "application/json"),
          "role");
  refused(client().Post("/api/v1/labels", counter(),
                        R"({"pincodes": ["110001"], "size": "a6", "size": "4x6in"})",
                        "application/json"),
          "size");
  // The same key in two objects is no duplicate.
  ExpectJson(client().Post("/api/v1/pincodes", admin(),
                           R"({"pincode": "999005", "offices": [{"name": "A", "district": "D",
                               "state": "S", "circle": "C", "region": "R", "division": "V"},
                               {"name": "B", "district": "D", "state": "S", "circle": "C",
                               "region": "R", "division": "V"}]})",
                           "application/json"),
             201);
}

// Every JSON body reads its optional fields alike: null is leaving the field out (an item's
// "office" was read so, while a batch's "size" and "plan", a token's "label" and a plan's
// "description" were refused); and a pincode is six digits as a string or a number, in an office
// as at the top (an office's own "pincode" had to be a string).
TEST_F(ServeTest, EveryBodyTakesNullForAnOptionalFieldLeftOut) {
  const auto labels =
      client().Post("/api/v1/labels?size=100x150mm", counter(),
                    R"({"pincodes": ["110001"], "size": null, "plan": null})", "application/json");
  ASSERT_TRUE(labels);
  EXPECT_EQ(labels->status, 200) << labels->body.substr(0, 300);
  EXPECT_EQ(labels->get_header_value("Content-Type"), "application/pdf");
  const json size_refused =
      ExpectProblem(client().Post("/api/v1/labels", counter(),
                                  R"({"pincodes": ["110001"], "plan": 7})", "application/json"),
                    400);
  EXPECT_NE(size_refused["detail"].get<std::string>().find("'plan' must be a string or null"),
            std::string::npos)
      << size_refused;

  const json token =
      ExpectJson(client().Post("/api/v1/tokens", admin(), R"({"role": "scanner", "label": null})",
                               "application/json"),
                 201);
  EXPECT_EQ(token["label"], "");

  ExpectJson(client().Put("/api/v1/sortplans/nulls", admin(),
                          R"({"name": null, "fallback_bin": "m", "description": null,
                              "rules": [{"prefix": "11", "bin": "north"}]})",
                          "application/json"),
             201);
  const json plan = ExpectJson(client().Get("/api/v1/sortplans/nulls"));
  EXPECT_EQ(plan["description"], "");
  EXPECT_EQ(plan["rules"].size(), 1U);
  // A required field given null is missing, and said so.
  const json no_fallback =
      ExpectProblem(client().Put("/api/v1/sortplans/nulls", admin(),
                                 R"({"fallback_bin": null, "rules": []})", "application/json"),
                    400);
  EXPECT_NE(no_fallback["detail"].get<std::string>().find("'fallback_bin' is required"),
            std::string::npos)
      << no_fallback;

  const std::string office = R"("name": "Alpha", "district": "North", "state": "S",
      "circle": "C", "region": "R", "division": "D")";
  const json other = ExpectProblem(
      client().Post("/api/v1/pincodes", admin(),
                    R"({"pincode": "999021", "offices": [{)" + office + R"(, "pincode": 999022}]})",
                    "application/json"),
      400);
  EXPECT_NE(other["detail"].get<std::string>().find("office 1: 'pincode' 999022 is not the "
                                                    "pincode being added"),
            std::string::npos)
      << other;
  ExpectProblem(client().Get("/api/v1/pincodes/999021"), 404);
  ExpectJson(client().Post("/api/v1/pincodes", admin(),
                           R"({"pincode": 999021, "offices": [{)" + office +
                               R"(, "pincode": 999021, "taluk": null}]})",
                           "application/json"),
             201);
  EXPECT_EQ(ExpectJson(client().Get("/api/v1/pincodes/999021"))["offices"][0]["name"], "Alpha");
}

}  // namespace
}  // namespace pintag::serve_test
