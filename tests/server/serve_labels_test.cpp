// Tags and labels of a real `pintag serve`, with the registry behind them.

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cctype>
#include <cstdio>
#include <regex>
#include <sstream>

#include "serve_fixture.hpp"

namespace pintag::serve_test {
namespace {

using nlohmann::json;

std::string Capture(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  ::pclose(pipe);
  return out;
}

OIIO::ImageSpec PngSpec(const std::string& bytes) {
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  OIIO::Filesystem::IOProxy* proxy = &reader;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = OIIO::ImageInput::open("x.png", &config);
  return in ? in->spec() : OIIO::ImageSpec();
}

/// The metrics line `name value`, or "" when it is not there.
std::string MetricLine(const std::string& metrics, const std::string& name) {
  std::smatch m;
  return std::regex_search(metrics, m, std::regex("\\n(" + name + " [^\\n]*)")) ? m[1].str() : "";
}

TEST_F(ServeTest, LabelsAndTagsComeAtTheAskedSizeAndResolution) {
  auto r = client().Get("/api/v1/labels/110001.pdf", counter());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/pdf");
  EXPECT_EQ(r->body.rfind("%PDF-", 0), 0U);
  // 100 x 150 mm in points (1 pt = 25.4 / 72 mm): 283.4646 x 425.1969.
  EXPECT_NE(r->body.find("/MediaBox [ 0 0 283.464567 425.19685 ]"), std::string::npos);

  r = client().Get("/api/v1/labels/110001.png?size=a6&dpi=150", counter());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  const OIIO::ImageSpec label = PngSpec(r->body);
  EXPECT_EQ(label.width, 620);   // 105 mm at 150 dpi
  EXPECT_EQ(label.height, 874);  // 148 mm at 150 dpi
  EXPECT_NEAR(label.get_float_attribute("XResolution"), 150, 0.03);

  r = client().Get("/api/v1/labels/560001.svg?size=4x6in", counter());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/svg+xml");
  EXPECT_NE(r->body.find("width=\"101.6000mm\""), std::string::npos);
  // Opened in a tab an SVG is a document: it may run and load nothing; and no answer is sniffed.
  EXPECT_EQ(r->get_header_value("Content-Security-Policy"),
            "default-src 'none'; style-src 'unsafe-inline'; img-src data:");
  EXPECT_EQ(r->get_header_value("X-Content-Type-Options"), "nosniff");

  r = client().Get("/api/v1/tags/110001.png?px=128&dpi=600", counter());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  const OIIO::ImageSpec tag = PngSpec(r->body);
  EXPECT_EQ(tag.width, 128 + 2 * 20);  // ceil(0.15 x 128) = 20 px quiet zone each side
  EXPECT_NEAR(tag.get_float_attribute("XResolution"), 600, 0.03);
  r = client().Get("/api/v1/tags/110001.svg?mm=30", counter());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_NE(r->body.find("key 11684"), std::string::npos);  // 110001's key in the seed
  EXPECT_NE(r->get_header_value("Content-Security-Policy").find("default-src 'none'"),
            std::string::npos);
  for (const char* path : {"/livez", "/api/v1/nothing", "/api/v1/pincodes/110001"}) {
    const auto answer = client().Get(path);
    ASSERT_TRUE(answer);
    EXPECT_EQ(answer->get_header_value("X-Content-Type-Options"), "nosniff") << path;
    EXPECT_EQ(answer->get_header_value_count("X-Content-Type-Options"), 1U) << path;
  }

  const std::string metrics = client().Get("/metrics")->body;
  EXPECT_EQ(MetricLine(metrics, "pintag_labels_rendered_total"), "pintag_labels_rendered_total 3");
  EXPECT_EQ(MetricLine(metrics, "pintag_tags_rendered_total"), "pintag_tags_rendered_total 2");
}

TEST_F(ServeTest, PngsLargerThanThePixelBudgetWaitTheirTurnAndComeWhole) {
  // A 300 dpi label (1181 x 1772 px) and a tag of 1024 px (1332 px with its quiet zone) are each
  // larger than this whole budget: each runs alone, in turn, and every one is answered whole.
  startServer({"--max-pixels", "1000000", "--max-pixels-in-flight", "1000000"});
  constexpr int kCounters = 4, kEach = 2;
  const auto waits = [&] {
    return Metric(client().Get("/metrics")->body, "pintag_pixel_budget_waits_total");
  };
  const auto png_of_size = [](const httplib::Result& r, int width, int height) {
    if (!r || r->status != 200) return false;
    const OIIO::ImageSpec spec = PngSpec(r->body);
    return spec.width == width && spec.height == height;
  };
  EXPECT_EQ(CallsRightFromConcurrentClients(
                server_->port(), kCounters, kEach,
                [&](httplib::Client& c) {
                  return png_of_size(c.Get("/api/v1/labels/110001.png", counter()), 1181, 1772);
                }),
            kCounters * kEach);
  const double after_labels = waits();
  EXPECT_GE(after_labels, 1.0);
  EXPECT_EQ(CallsRightFromConcurrentClients(
                server_->port(), kCounters, kEach,
                [&](httplib::Client& c) {
                  return png_of_size(c.Get("/api/v1/tags/110001.png?px=1024", counter()), 1332,
                                     1332);
                }),
            kCounters * kEach);
  EXPECT_GE(waits(), after_labels + 1);
}

// A form's blank size field sends "size=" (or "size": ""), which was 400 "empty label size"
// where a blank plan or office is the default: the default size now, as theirs.
TEST_F(ServeTest, ABlankLabelSizeIsTheDefault) {
  const auto width_of = [&](const std::string& path) {
    const auto r = client().Get(path, counter());
    EXPECT_TRUE(r && r->status == 200) << path << (r ? r->body : "");
    return r && r->status == 200 ? PngSpec(r->body).width : -1;
  };
  const int default_width = width_of("/api/v1/labels/110001.png?dpi=100");
  EXPECT_GT(default_width, 0);
  EXPECT_EQ(width_of("/api/v1/labels/110001.png?dpi=100&size="), default_width);
  EXPECT_NE(width_of("/api/v1/labels/110001.png?dpi=100&size=a6"), default_width);
  const auto batch = client().Post("/api/v1/labels", counter(),
                                   R"({"pincodes": ["110001"], "size": ""})", "application/json");
  ASSERT_TRUE(batch);
  EXPECT_EQ(batch->status, 200) << batch->body.substr(0, 300);
}

TEST_F(ServeTest, LabelProblemsSayWhatIsWrong) {
  const auto expect = [&](const std::string& path, int status, const std::string& fragment) {
    const json problem = ExpectProblem(client().Get(path, counter()), status);
    EXPECT_NE(problem.dump().find(fragment), std::string::npos) << path << ": " << problem;
  };
  expect("/api/v1/labels/11001.pdf", 400, "6 digits");
  expect("/api/v1/labels/011001.pdf", 400, "Malformed Pincode");
  expect("/api/v1/labels/110001.pdf?size=100x150", 400, "needs a unit");
  expect("/api/v1/labels/110001.pdf?size=10x10mm", 400, "50 to 300 mm");
  expect("/api/v1/labels/110001.pdf?size=60x60mm", 400, "at least 20 mm");
  expect("/api/v1/labels/110001.png?dpi=5000", 400, "'dpi'");
  expect("/api/v1/labels/110001.png?dpi=abc", 400, "'dpi'");
  expect("/api/v1/labels/110001.png?size=300x300mm&dpi=1200", 400, "megapixels");
  expect("/api/v1/tags/110001.png?px=5000", 400, "'px'");
  expect("/api/v1/tags/110001.png?px=128.5", 400, "must be an integer");
  expect("/api/v1/tags/110001.svg?px=100&mm=10", 400, "at most one");
  const std::string metrics = client().Get("/metrics")->body;
  EXPECT_EQ(MetricLine(metrics, "pintag_labels_rendered_total"), "pintag_labels_rendered_total 0");
}

// Two bins of a plan that differ in their middle printed alike on a small label, each cut to
// "Kolkata… / nd Bay 12": a label whose bin cannot print whole is refused, naming it, and prints
// on a size that holds it.
TEST_F(ServeTest, ALabelWhoseBinCannotPrintWholeIsRefusedNamingIt) {
  ExpectJson(client().Put("/api/v1/sortplans/pair", admin(),
                          "prefix,bin\n*,floor\n110001,Kolkata Inbound Bay 12\n"
                          "110002,Kolkata Outbound Bay 12\n",
                          "text/csv"),
             201);
  for (const char* format : {"pdf", "png", "svg"}) {
    const json refused = ExpectProblem(
        client().Get(std::string("/api/v1/labels/110001.") + format + "?size=70x50mm&plan=pair",
                     counter()),
        400);
    EXPECT_EQ(refused["title"], "Cannot Render Label") << refused;
    EXPECT_NE(refused["detail"].get<std::string>().find("'Kolkata Inbound Bay 12'"),
              std::string::npos)
        << refused;
  }
  // In a batch, named by its place as an item's other problems are (110003 gets the fallback bin).
  const json batch = ExpectProblem(
      client().Post("/api/v1/labels?size=70x50mm&plan=pair", counter(),
                    R"({"pincodes": ["110003", "110001", "110002"]})", "application/json"),
      400);
  EXPECT_EQ(
      batch["detail"].get<std::string>().rfind("pincodes[1]: the sort bin 'Kolkata Inbound", 0), 0U)
      << batch;
  const auto whole = client().Get("/api/v1/labels/110002.pdf?plan=pair", counter());
  ASSERT_TRUE(whole);
  EXPECT_EQ(whole->status, 200) << whole->body;
  const std::string metrics = client().Get("/metrics")->body;
  EXPECT_EQ(MetricLine(metrics, "pintag_labels_rendered_total"), "pintag_labels_rendered_total 1");
}

TEST_F(ServeTest, BatchProblemsNameTheBadInput) {
  const auto expect = [&](const std::string& body, int status, const std::string& fragment) {
    const json problem =
        ExpectProblem(client().Post("/api/v1/labels", counter(), body, "application/json"), status);
    EXPECT_NE(problem.dump().find(fragment), std::string::npos) << body << ": " << problem;
  };
  expect("not json", 400, "not valid JSON");
  expect(R"({"pincodes": []})", 400, "empty");
  expect(R"({"pins": ["110001"]})", 400, "expected");
  expect(R"({"pincodes": [110001.5]})", 400, "pincodes[0]");
  expect(R"({"pincodes": [true]})", 400, "pincodes[0] must be six digits, as a string");
  expect(R"({"pincodes": ["110001", "abc"]})", 400, "pincodes[1]");
  expect(R"({"pincodes": ["110001"], "size": 5})", 400, "'size' must be a string or null");
  expect(R"({"pincodes": ["110001"], "plan": "nope"})", 404, "Unknown Sort Plan");
  // A misspelt field printed the default plan's bins or size unnoticed (a reviewer's "Plan").
  expect(R"({"pincodes": ["110001"], "Plan": "default"})", 400, "unknown field 'Plan'");
  expect(R"({"pincodes": ["110001"], "szie": "a6"})", 400, "unknown field 'szie'");
  // Given in the body and the query, a plan or a size must be the same: the body's won silently.
  for (const auto& [query, body, fragment] :
       {std::tuple{"?plan=default", R"({"pincodes": ["110001"], "plan": "ov"})",
                   "'plan' is given twice: 'ov' in the body and 'default' in the query"},
        std::tuple{"?size=a6", R"({"pincodes": ["110001"], "size": "100x150mm"})",
                   "'size' is given twice"}}) {
    const json problem = ExpectProblem(
        client().Post(std::string("/api/v1/labels") + query, counter(), body, "application/json"),
        400);
    EXPECT_NE(problem.dump().find(fragment), std::string::npos) << problem;
  }
  // The same size written otherwise ("A6", "a6") is the same size.
  const auto same = client().Post("/api/v1/labels?plan=default&size=a6", counter(),
                                  R"({"pincodes": ["110001"], "plan": "default", "size": "A6"})",
                                  "application/json");
  ASSERT_TRUE(same);
  EXPECT_EQ(same->status, 200) << same->body.substr(0, 300);
  // A bare list of pincodes (strings or numbers) is a batch too.
  const auto r =
      client().Post("/api/v1/labels", counter(), R"(["110001", 560001])", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body.substr(0, 300);
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/pdf");
}

TEST_F(ServeTest, TagsAndLabelsForARealPincode) {
  auto r = client().Get("/api/v1/tags/110001.png?px=128", counter());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(r->body.substr(1, 3), "PNG");
  r = client().Get("/api/v1/tags/110001.svg?mm=30", counter());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_NE(r->body.find("<svg"), std::string::npos);
  for (const char* format : {"pdf", "png", "svg"}) {
    r = client().Get(std::string("/api/v1/labels/110001.") + format + "?plan=default&size=a6",
                     admin());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << format << " " << r->body.substr(0, 300);
  }
  // The label names the plan's bin: the default plan sends 11xxxx to bin "11".
  r = client().Get("/api/v1/labels/110001.svg?plan=default", counter());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
}

TEST_F(ServeTest, LabelErrors) {
  ExpectProblem(client().Get("/api/v1/labels/110001.pdf"), 401);
  ExpectProblem(client().Get("/api/v1/labels/110001.pdf", Auth("not-a-token")), 401);
  ExpectProblem(client().Get("/api/v1/labels/110001.pdf", scanner()), 403);
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/labels/999999.pdf", counter()), 404)["title"],
            "Unknown Pincode");
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/tags/999999.png", counter()), 404)["title"],
            "Unknown Pincode");
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/labels/11001.pdf", counter()), 400)["title"],
            "Malformed Pincode");
  EXPECT_EQ(ExpectProblem(client().Get("/api/v1/labels/110001.pdf?size=10x10mm", counter()),
                          400)["title"],
            "Bad Label Size");
  ExpectProblem(client().Get("/api/v1/labels/110001.pdf?size=100x150", counter()), 400);
  ExpectProblem(client().Get("/api/v1/labels/110001.png?dpi=5000", counter()), 400);
  ExpectProblem(client().Get("/api/v1/tags/110001.png?px=100000", counter()), 400);
  EXPECT_EQ(
      ExpectProblem(client().Get("/api/v1/labels/110001.pdf?plan=nope", counter()), 404)["title"],
      "Unknown Sort Plan");

  // A retired pincode: refused with a clear problem, while its key still looks up.
  ExpectJson(client().Post("/api/v1/pincodes/110002/retire", admin(), "", "text/plain"));
  const json problem = ExpectProblem(client().Get("/api/v1/labels/110002.pdf", counter()), 410);
  EXPECT_EQ(problem["title"], "Retired Pincode");
  EXPECT_NE(problem["detail"].get<std::string>().find("110002 was retired"), std::string::npos);
  ExpectProblem(client().Get("/api/v1/tags/110002.png", counter()), 410);
  ExpectProblem(client().Post("/api/v1/labels", counter(), R"({"pincodes": ["110001", "110002"]})",
                              "application/json"),
                410);
}

/// The lines of text on page `page` of a PDF, as pdftotext reads them.
std::vector<std::string> PdfLines(const TempDir& dir, const std::string& pdf, int page) {
  const std::string file = dir.file("text.pdf");
  WriteFile(file, pdf);
  const std::string text = Capture("pdftotext -f " + std::to_string(page) + " -l " +
                                   std::to_string(page) + " " + file + " -");
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

bool HasLine(const std::vector<std::string>& lines, const std::string& line) {
  return std::find(lines.begin(), lines.end(), line) != lines.end();
}

// A counter clerk who never picks a plan still prints the bin: labels and batches without `plan`
// use the default sort plan, the same bin GET /api/v1/route/{pin} answers.
TEST_F(ServeTest, LabelsWithoutAPlanPrintTheDefaultPlansBin) {
  ASSERT_EQ(std::system("command -v pdftotext > /dev/null 2>&1"), 0)
      << "pdftotext is missing: install poppler-utils (scripts/debian-packages-test.txt)";
  std::vector<std::string> bins;
  for (const char* pin : {"560001", "110001"}) {
    const json routed = ExpectJson(client().Get(std::string("/api/v1/route/") + pin));
    ASSERT_EQ(routed["plan"], "default");
    bins.push_back(routed["bin"]);
    auto r = client().Get(std::string("/api/v1/labels/") + pin + ".pdf", counter());
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body.substr(0, 300);
    const std::vector<std::string> lines = PdfLines(dir_, r->body, 1);
    EXPECT_TRUE(HasLine(lines, "SORT BIN")) << pin;
    EXPECT_TRUE(HasLine(lines, bins.back())) << pin << " bin " << bins.back();
    EXPECT_TRUE(HasLine(lines, "plan default")) << pin;
    EXPECT_FALSE(HasLine(lines, "none")) << pin;
  }
  ASSERT_NE(bins[0], bins[1]);  // so each page below is checked against its own bin
  const auto r = client().Post("/api/v1/labels", counter(), R"({"pincodes": ["560001", "110001"]})",
                               "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body.substr(0, 300);
  for (int page = 1; page <= 2; ++page) {
    const std::vector<std::string> lines = PdfLines(dir_, r->body, page);
    EXPECT_TRUE(HasLine(lines, bins[page - 1])) << "page " << page;
    EXPECT_TRUE(HasLine(lines, "plan default")) << "page " << page;
    EXPECT_FALSE(HasLine(lines, "none")) << "page " << page;
  }
  // The OpenAPI document says so for every label route.
  const json doc = ExpectJson(client().Get("/openapi.json"));
  for (const auto& [path, method] :
       {std::pair{"/api/v1/labels/{pin}.pdf", "get"}, std::pair{"/api/v1/labels/{pin}.png", "get"},
        std::pair{"/api/v1/labels/{pin}.svg", "get"}, std::pair{"/api/v1/labels", "post"}}) {
    bool documented = false;
    for (const json& parameter : doc["paths"][path][method]["parameters"]) {
      documented = documented ||
                   (parameter["name"] == "plan" && parameter["description"].get<std::string>().find(
                                                       "(default: default)") != std::string::npos);
    }
    EXPECT_TRUE(documented) << method << " " << path;
  }
}

// A pincode serves many offices (110001: 21); the clerk can print the addressee's.
TEST_F(ServeTest, ALabelPrintsTheOfficeAskedFor) {
  ASSERT_EQ(std::system("command -v pdftotext > /dev/null 2>&1"), 0)
      << "pdftotext is missing: install poppler-utils (scripts/debian-packages-test.txt)";
  const json record = ExpectJson(client().Get("/api/v1/pincodes/110001"));
  ASSERT_GT(record["offices"].size(), 2U);
  const std::string main_office = record["office"];
  std::string other;  // an office of 110001 that is not the one printed by default
  for (const json& office : record["offices"]) {
    if (office["name"] != main_office) other = office["name"];
  }
  ASSERT_FALSE(other.empty());
  std::string typed = other;  // as a clerk might type it: lower case, a space after
  for (char& c : typed) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  typed += " ";

  std::string query;  // percent-encoded
  for (const char c : typed) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      query += c;
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", static_cast<unsigned char>(c));
      query += hex;
    }
  }
  auto single = client().Get("/api/v1/labels/110001.pdf?office=" + query, counter());
  ASSERT_TRUE(single);
  ASSERT_EQ(single->status, 200) << single->body.substr(0, 300);
  std::vector<std::string> lines = PdfLines(dir_, single->body, 1);
  EXPECT_TRUE(HasLine(lines, other)) << other;
  EXPECT_FALSE(HasLine(lines, main_office)) << main_office;
  lines = PdfLines(dir_, client().Get("/api/v1/labels/110001.pdf", counter())->body, 1);
  EXPECT_TRUE(HasLine(lines, main_office)) << "without office=, the main office";

  const json batch = {{"pincodes", {"110001", {{"pincode", "110001"}, {"office", other}}}}};
  auto both = client().Post("/api/v1/labels", counter(), batch.dump(), "application/json");
  ASSERT_TRUE(both);
  ASSERT_EQ(both->status, 200) << both->body.substr(0, 300);
  EXPECT_TRUE(HasLine(PdfLines(dir_, both->body, 1), main_office));
  EXPECT_TRUE(HasLine(PdfLines(dir_, both->body, 2), other));
  // "office": null is the same as no office: the main one.
  auto unnamed =
      client().Post("/api/v1/labels", counter(),
                    R"({"pincodes": [{"pincode": "110001", "office": null}]})", "application/json");
  ASSERT_TRUE(unnamed);
  ASSERT_EQ(unnamed->status, 200) << unnamed->body.substr(0, 300);
  EXPECT_TRUE(HasLine(PdfLines(dir_, unnamed->body, 1), main_office));

  // An office the pincode does not have is refused, naming some it has; so are bad items.
  const json unknown = ExpectProblem(
      client().Get("/api/v1/labels/110001.png?office=Nowhere%20Nagar", counter()), 400);
  EXPECT_EQ(unknown["title"], "Unknown Office");
  EXPECT_NE(unknown["detail"].get<std::string>().find(main_office), std::string::npos)
      << unknown.dump();
  for (const char* body : {R"({"pincodes": [{"pincode": "110001", "office": "Nowhere Nagar"}]})",
                           R"({"pincodes": [{"office": "Janpath"}]})",
                           R"({"pincodes": [{"pincode": "110001", "office": 7}]})",
                           R"({"pincodes": [{"pincode": "110001", "floor": "2"}]})"}) {
    const json problem =
        ExpectProblem(client().Post("/api/v1/labels", counter(), body, "application/json"), 400);
    EXPECT_NE(problem["detail"].get<std::string>().find("pincodes[0]"), std::string::npos)
        << body << " " << problem.dump();
  }
}

// A pincode's offices can lie in different districts: the place printed under the office is
// that office's, and the record's summary is its main office's (before, both were its first
// office's, so a label could print "Beta H.O" over Alpha's district).
TEST_F(ServeTest, ALabelPrintsThePlaceOfTheOfficeItNames) {
  ASSERT_EQ(std::system("command -v pdftotext > /dev/null 2>&1"), 0)
      << "pdftotext is missing: install poppler-utils (scripts/debian-packages-test.txt)";
  const std::string body = R"({"pincode": "999003", "offices": [
      {"name": "Alpha B.O", "branch_type": "BO", "district": "Ropar", "state": "Punjab",
       "circle": "Punjab", "region": "Chandigarh", "division": "Ropar"},
      {"name": "Beta H.O", "branch_type": "HO", "district": "Mohali", "state": "Haryana",
       "circle": "Haryana", "region": "Ambala", "division": "Mohali"}]})";
  ExpectJson(client().Post("/api/v1/pincodes", admin(), body, "application/json"), 201);
  const json record = ExpectJson(client().Get("/api/v1/pincodes/999003"));
  EXPECT_EQ(record["office"], "Beta H.O");
  EXPECT_EQ(record["district"], "Mohali");
  EXPECT_EQ(record["state"], "Haryana");
  EXPECT_EQ(record["division"], "Mohali");

  auto main_label = client().Get("/api/v1/labels/999003.pdf", counter());
  ASSERT_TRUE(main_label);
  ASSERT_EQ(main_label->status, 200) << main_label->body.substr(0, 300);
  std::vector<std::string> lines = PdfLines(dir_, main_label->body, 1);
  EXPECT_TRUE(HasLine(lines, "Beta H.O"));
  EXPECT_TRUE(HasLine(lines, "Mohali, Haryana"));
  auto alpha_label = client().Get("/api/v1/labels/999003.pdf?office=Alpha%20B.O", counter());
  ASSERT_TRUE(alpha_label);
  ASSERT_EQ(alpha_label->status, 200) << alpha_label->body.substr(0, 300);
  lines = PdfLines(dir_, alpha_label->body, 1);
  EXPECT_TRUE(HasLine(lines, "Alpha B.O"));
  EXPECT_TRUE(HasLine(lines, "Ropar, Punjab"));
  EXPECT_FALSE(HasLine(lines, "Mohali, Haryana"));
  const json batch = {{"pincodes", {{{"pincode", "999003"}, {"office", "Alpha B.O"}}}}};
  auto batched = client().Post("/api/v1/labels", counter(), batch.dump(), "application/json");
  ASSERT_TRUE(batched);
  ASSERT_EQ(batched->status, 200) << batched->body.substr(0, 300);
  EXPECT_TRUE(HasLine(PdfLines(dir_, batched->body, 1), "Ropar, Punjab"));
}

// Office names are told apart by case when stored, so the office named exactly is printed before
// one that matches only without case (a label printed "Twin, District A" when "TWIN" was asked).
TEST_F(ServeTest, ALabelPrintsTheOfficeNamedExactlyBeforeOneThatDiffersInCase) {
  ASSERT_EQ(std::system("command -v pdftotext > /dev/null 2>&1"), 0)
      << "pdftotext is missing: install poppler-utils (scripts/debian-packages-test.txt)";
  const std::string body = R"({"pincode": "999004", "offices": [
      {"name": "Twin", "branch_type": "BO", "district": "Ropar", "state": "Punjab",
       "circle": "Punjab", "region": "Chandigarh", "division": "Ropar"},
      {"name": "TWIN", "branch_type": "HO", "district": "Mohali", "state": "Haryana",
       "circle": "Haryana", "region": "Ambala", "division": "Mohali"}]})";
  ExpectJson(client().Post("/api/v1/pincodes", admin(), body, "application/json"), 201);
  for (const auto& [asked, place] :
       {std::pair{"Twin", "Ropar, Punjab"}, std::pair{"TWIN", "Mohali, Haryana"}}) {
    auto label = client().Get(std::string("/api/v1/labels/999004.pdf?office=") + asked, counter());
    ASSERT_TRUE(label);
    ASSERT_EQ(label->status, 200) << label->body.substr(0, 300);
    EXPECT_TRUE(HasLine(PdfLines(dir_, label->body, 1), place)) << asked;
  }
  // Without an exact match, the name still matches without case.
  auto typed = client().Get("/api/v1/labels/999004.pdf?office=twin", counter());
  ASSERT_TRUE(typed);
  EXPECT_EQ(typed->status, 200) << typed->body.substr(0, 300);
}

TEST_F(ServeTest, BatchPdfOf50LabelsHas50PagesOfTheRightSize) {
  ASSERT_EQ(std::system("command -v pdfinfo > /dev/null 2>&1"), 0)
      << "pdfinfo is missing: install poppler-utils (scripts/debian-packages-test.txt)";
  const json search = ExpectJson(client().Get("/api/v1/pincodes?state=Delhi&limit=500"));
  std::vector<std::string> pins;
  for (const json& hit : search["results"]) {
    const std::string pin = hit["pincode"];
    if (std::find(pins.begin(), pins.end(), pin) == pins.end()) pins.push_back(pin);
    if (pins.size() == 50) break;
  }
  ASSERT_EQ(pins.size(), 50U);
  const json body = {{"pincodes", pins}, {"size", "100x150mm"}, {"plan", "default"}};
  auto r = client().Post("/api/v1/labels", counter(), body.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body.substr(0, 300);
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/pdf");
  WriteFile(dir_.file("batch.pdf"), r->body);
  const std::string info = Capture("pdfinfo " + dir_.file("batch.pdf"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(info, m, std::regex(R"(Pages:\s+(\d+))"))) << info;
  EXPECT_EQ(std::stoi(m[1].str()), 50);
  // Every page 100 x 150 mm = 283.465 x 425.197 pt.
  const std::string pages = Capture("pdfinfo -f 1 -l 50 " + dir_.file("batch.pdf"));
  int sized = 0;
  const std::regex size_re(R"(Page\s+\d+ size:\s+([\d.]+) x ([\d.]+) pts)");
  for (auto it = std::sregex_iterator(pages.begin(), pages.end(), size_re);
       it != std::sregex_iterator(); ++it) {
    EXPECT_NEAR(std::stod((*it)[1].str()), 283.465, 0.01);
    EXPECT_NEAR(std::stod((*it)[2].str()), 425.197, 0.01);
    ++sized;
  }
  EXPECT_EQ(sized, 50);

  // More than the batch limit (100) is 413; an empty list 400.
  std::vector<std::string> many(101, "110001");
  ExpectProblem(client().Post("/api/v1/labels", counter(), json{{"pincodes", many}}.dump(),
                              "application/json"),
                413);
  ExpectProblem(
      client().Post("/api/v1/labels", counter(), R"({"pincodes": []})", "application/json"), 400);
  ExpectProblem(
      client().Post("/api/v1/labels", counter(), R"({"pincodes": ["11000"]})", "application/json"),
      400);
  ExpectProblem(
      client().Post("/api/v1/labels", counter(), R"({"pincodes": ["999999"]})", "application/json"),
      404);
}

// A server whose --max-tag-px is under the default tag size (256) renders its largest by
// default; before, the default was 256 whatever the limit, and px=256 was refused.
TEST_F(ServeTest, ATagLimitUnderTheDefaultSizeIsTheDefault) {
  startServer({"--max-tag-px", "128"});
  auto r = client().Get("/api/v1/tags/110001.png", counter());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(PngSpec(r->body).width, 128 + 2 * 20);  // 128 px and its quiet zone
  ExpectProblem(client().Get("/api/v1/tags/110001.png?px=256", counter()), 400);
  r = client().Get("/api/v1/tags/110001.png?px=64", counter());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  // And /openapi.json says that default (it said 256 whatever the limit).
  const json doc = ExpectJson(client().Get("/openapi.json"));
  std::string px;
  for (const json& parameter : doc["paths"]["/api/v1/tags/{pin}.png"]["get"]["parameters"]) {
    if (parameter["name"] == "px") px = parameter["description"];
  }
  EXPECT_NE(px.find("64 to 128 (default 128)"), std::string::npos) << px;
}

}  // namespace
}  // namespace pintag::serve_test
