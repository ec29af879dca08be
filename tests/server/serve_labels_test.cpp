// Tags and labels of a real `pintag serve`, with the registry behind them.

#include <cstdio>
#include <regex>

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

TEST_F(ServeTest, BatchPdfOf50LabelsHas50PagesOfTheRightSize) {
  if (std::system("command -v pdfinfo > /dev/null 2>&1") != 0) GTEST_SKIP() << "no pdfinfo";
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

}  // namespace
}  // namespace pintag::serve_test
