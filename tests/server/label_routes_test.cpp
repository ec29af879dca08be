#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "test_support.hpp"

namespace pintag::server {
namespace {

using test::Get;

class LabelRoutesTest : public ::testing::Test {
 protected:
  LabelRoutesTest()
      : metrics_(std::make_shared<Metrics>()),
        api_(test::TestRouter(metrics_), test::FakeVerifier(), nullptr, metrics_) {}

  HttpResponse call(const std::string& path) { return api_.handle(Get(path, test::kCounterToken)); }

  HttpResponse batch(const std::string& json) {
    HttpRequest r = Get("/api/v1/labels", test::kCounterToken);
    r.method = "POST";
    r.headers.emplace("Content-Type", "application/json");
    r.headers.emplace("Content-Length", std::to_string(json.size()));
    r.body = json;
    return api_.handle(r);
  }

  void expectProblem(const HttpResponse& r, int status, const std::string& fragment) {
    EXPECT_EQ(r.status, status) << r.body;
    EXPECT_EQ(r.content_type, "application/problem+json");
    EXPECT_NE(r.body.find(fragment), std::string::npos) << r.body;
  }

  std::shared_ptr<Metrics> metrics_;
  Api api_;
};

OIIO::ImageSpec PngSpec(const std::string& bytes) {
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  OIIO::Filesystem::IOProxy* proxy = &reader;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = OIIO::ImageInput::open("x.png", &config);
  return in ? in->spec() : OIIO::ImageSpec();
}

TEST_F(LabelRoutesTest, LabelInEachFormat) {
  HttpResponse r = call("/api/v1/labels/110001.pdf?plan=north");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "application/pdf");
  EXPECT_EQ(r.body.rfind("%PDF-", 0), 0U);
  EXPECT_NE(r.body.find("/MediaBox [ 0 0 283.464567 425.19685 ]"), std::string::npos);

  r = call("/api/v1/labels/110001.png?size=a6&dpi=150");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "image/png");
  const OIIO::ImageSpec spec = PngSpec(r.body);
  EXPECT_EQ(spec.width, 620);
  EXPECT_EQ(spec.height, 874);
  EXPECT_NEAR(spec.get_float_attribute("XResolution"), 150, 0.03);

  r = call("/api/v1/labels/560001.svg?size=4x6in");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "image/svg+xml");
  EXPECT_NE(r.body.find("width=\"101.6000mm\""), std::string::npos);
  EXPECT_EQ(metrics_->counter(kLabelsRenderedCounter), 3);
}

TEST_F(LabelRoutesTest, TagImages) {
  HttpResponse r = call("/api/v1/tags/110001.png?px=128&dpi=600");
  ASSERT_EQ(r.status, 200) << r.body;
  const OIIO::ImageSpec spec = PngSpec(r.body);
  EXPECT_EQ(spec.width, 128 + 2 * 20);  // ceil(0.15 × 128) = 20 px quiet zone each side
  EXPECT_NEAR(spec.get_float_attribute("XResolution"), 600, 0.03);
  r = call("/api/v1/tags/110001.svg?mm=30");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_NE(r.body.find("key 12345"), std::string::npos);
  EXPECT_EQ(metrics_->counter(kTagsRenderedCounter), 2);
}

TEST_F(LabelRoutesTest, ClearProblems) {
  expectProblem(call("/api/v1/labels/11001.pdf"), 400, "6 digits");
  expectProblem(call("/api/v1/labels/011001.pdf"), 400, "Malformed Pincode");
  expectProblem(call("/api/v1/labels/999999.pdf"), 404, "not in the registry");
  expectProblem(call("/api/v1/labels/110002.pdf"), 410, "retired");
  expectProblem(call("/api/v1/labels/110001.pdf?plan=south"), 404, "no sort plan");
  expectProblem(call("/api/v1/labels/110001.pdf?size=100x150"), 400, "needs a unit");
  expectProblem(call("/api/v1/labels/110001.pdf?size=10x10mm"), 400, "50 to 300 mm");
  expectProblem(call("/api/v1/labels/110001.png?dpi=5000"), 400, "'dpi'");
  expectProblem(call("/api/v1/labels/110001.png?dpi=abc"), 400, "'dpi'");
  expectProblem(call("/api/v1/labels/110001.png?size=300x300mm&dpi=1200"), 400, "megapixels");
  expectProblem(call("/api/v1/tags/110001.png?px=5000"), 400, "'px'");
  expectProblem(call("/api/v1/tags/110001.svg?px=100&mm=10"), 400, "at most one");
  EXPECT_EQ(metrics_->counter(kLabelsRenderedCounter), 0);
}

TEST_F(LabelRoutesTest, LabelsNeedACounterOrAdminToken) {
  EXPECT_EQ(api_.handle(Get("/api/v1/labels/110001.pdf")).status, 401);
  EXPECT_EQ(api_.handle(Get("/api/v1/labels/110001.pdf", test::kScannerToken)).status, 403);
  EXPECT_EQ(api_.handle(Get("/api/v1/labels/110001.pdf", test::kAdminToken)).status, 200);
}

TEST_F(LabelRoutesTest, BatchPdfHasAPagePerPincode) {
  std::string json = R"({"size": "a6", "plan": "north", "pincodes": [)";
  for (int i = 0; i < 50; ++i)
    json += std::string(i ? "," : "") + (i % 2 ? "\"110001\"" : "560001");
  json += "]}";
  const HttpResponse r = batch(json);
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "application/pdf");
  int pages = 0;
  for (std::size_t at = r.body.find("/MediaBox [ 0 0 297.637795 419.527559 ]");
       at != std::string::npos;
       at = r.body.find("/MediaBox [ 0 0 297.637795 419.527559 ]", at + 1)) {
    ++pages;
  }
  EXPECT_EQ(pages, 50);
  EXPECT_EQ(metrics_->counter(kLabelsRenderedCounter), 50);
  EXPECT_EQ(batch(R"(["110001", "560001"])").status, 200);  // a bare array works too
}

TEST_F(LabelRoutesTest, BatchProblems) {
  expectProblem(batch("not json"), 400, "not valid JSON");
  expectProblem(batch(R"({"pincodes": []})"), 400, "empty");
  expectProblem(batch(R"({"pins": ["110001"]})"), 400, "expected");
  expectProblem(batch(R"({"pincodes": [110001.5]})"), 400, "pincodes[0]");
  expectProblem(batch(R"({"pincodes": ["110001", "abc"]})"), 400, "pincodes[1]");
  expectProblem(batch(R"({"pincodes": ["110001", "110002"]})"), 410, "retired");
  expectProblem(batch(R"({"pincodes": ["110001"], "size": 5})"), 400, "'size' must be a string");
  std::string many = "[";
  for (int i = 0; i < 61; ++i) many += std::string(i ? "," : "") + "\"110001\"";
  expectProblem(batch(many + "]"), 413, "at most 60 labels");
}

}  // namespace
}  // namespace pintag::server
