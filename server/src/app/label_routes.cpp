// Tag and label routes: a pincode's PinTag alone (PNG, SVG) and its printable label (PDF, PNG,
// SVG; many as one PDF). Labels print the bin of the asked sort plan, the default plan when none
// is asked for. Unknown pincodes are 404, retired ones 410.

#include <vector>

#include "app/db_problems.hpp"
#include "app/params.hpp"
#include "app/registry_json.hpp"
#include "app/routes.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/png_io.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/codec/tag_svg.hpp"

namespace pintag::app {
namespace {

constexpr int kDefaultTagPx = 256;
constexpr double kDefaultTagMm = 50;
constexpr double kMinTagMm = 5;
constexpr double kMaxTagMm = 500;

// What a label prints for an active pincode under `plan`.
LabelContent LabelFor(const db::PincodeRecord& record, const db::SortPlan& plan) {
  LabelContent label;
  label.pincode = record.pincode;
  label.key = record.key;
  if (const db::PostOffice* office = MainOffice(record)) label.office = office->name;
  label.district = record.district;
  label.state = record.state;
  label.plan = plan.name;
  label.bin = db::RouteWith(plan, record.pincode).bin;
  return label;
}

HttpResponse Named(HttpResponse response, const std::string& filename) {
  response.headers.emplace_back("Content-Disposition", "inline; filename=\"" + filename + "\"");
  response.headers.emplace_back("Cache-Control", "no-cache");
  return response;
}

HttpResponse Rendered(const RenderedLabel& rendered, const AppContext& context, std::string type,
                      const std::string& filename, std::size_t labels = 1) {
  if (!rendered) throw HttpError(400, rendered.error, "Cannot Render Label");
  context.metrics->increment(kLabelsRenderedCounter, static_cast<double>(labels));
  return Named(HttpResponse::Bytes(std::move(type), rendered.bytes), filename);
}

// One label: its options and content from the request and the registry.
struct LabelRequest {
  LabelContent content;
  LabelOptions options;
};

LabelRequest ReadLabelRequest(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  LabelRequest label;
  label.options.size = LabelSizeQuery(request);
  label.options.dpi = DpiQuery(request);
  const std::string plan_name = PlanQuery(request);
  auto connection = context.pool->acquire();
  const db::PincodeRecord record = LoadActivePincode(*connection, pincode);
  label.content = LabelFor(record, LoadPlan(*connection, plan_name));
  return label;
}

TagKey ActiveKey(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  auto connection = context.pool->acquire();
  return LoadActivePincode(*connection, pincode).key;
}

}  // namespace

HttpResponse GetTagPng(const AppContext& context, const HttpRequest& request) {
  const long long px =
      IntegerQuery(request, "px", kDefaultTagPx, kMinTagSquarePx, context.max_tag_px);
  const double dpi = DpiQuery(request);
  const TagKey key = ActiveKey(context, request);
  const long long side = px + 2LL * QuietZonePx(static_cast<int>(px));  // the PNG's side
  const PixelBudget::Reservation pixels = HoldPixels(context, side * side);
  const TagRaster raster = RenderTagRaster(key, {static_cast<int>(px), 4});
  std::string error;
  const std::vector<std::uint8_t> png = EncodePng(raster.image, dpi, &error);
  if (!error.empty()) throw std::runtime_error(error);
  context.metrics->increment(kTagsRenderedCounter);
  return Named(HttpResponse::Bytes("image/png", png), "tag-" + request.pathParam("pin") + ".png");
}

HttpResponse GetTagSvg(const AppContext& context, const HttpRequest& request) {
  if (request.queryParam("mm") && request.queryParam("px")) {
    throw HttpError(400, "give at most one of 'mm' and 'px'");
  }
  const TagSvgOptions svg =
      request.queryParam("px")
          ? TagSvgOptions{*NumberQuery(request, "px", kMinTagSquarePx, context.max_tag_px), "px"}
          : TagSvgOptions{NumberQuery(request, "mm", kMinTagMm, kMaxTagMm).value_or(kDefaultTagMm),
                          "mm"};
  const TagKey key = ActiveKey(context, request);
  context.metrics->increment(kTagsRenderedCounter);
  return Named(HttpResponse::Bytes("image/svg+xml", RenderTagSvg(key, svg)),
               "tag-" + request.pathParam("pin") + ".svg");
}

HttpResponse GetLabelPdf(const AppContext& context, const HttpRequest& request) {
  const LabelRequest label = ReadLabelRequest(context, request);
  return Rendered(RenderLabelPdf(label.content, label.options), context, "application/pdf",
                  "label-" + label.content.pincode.str() + ".pdf");
}

HttpResponse GetLabelPng(const AppContext& context, const HttpRequest& request) {
  const LabelRequest label = ReadLabelRequest(context, request);
  // Options out of range are refused by the renderer without a raster: nothing to hold for them.
  PixelBudget::Reservation pixels;
  if (ValidateLabelOptions(label.options, /*raster=*/true).empty()) {
    const PixelSize size = LabelPixelSize(label.options);
    pixels = HoldPixels(context, std::int64_t{size.width} * size.height);
  }
  return Rendered(RenderLabelPng(label.content, label.options), context, "image/png",
                  "label-" + label.content.pincode.str() + ".png");
}

HttpResponse GetLabelSvg(const AppContext& context, const HttpRequest& request) {
  const LabelRequest label = ReadLabelRequest(context, request);
  return Rendered(RenderLabelSvg(label.content, label.options), context, "image/svg+xml",
                  "label-" + label.content.pincode.str() + ".svg");
}

HttpResponse PostLabels(const AppContext& context, const HttpRequest& request) {
  json body = JsonBody(request);
  if (body.is_array()) body = json{{"pincodes", body}};
  if (!body.is_object() || !body.contains("pincodes") || !body["pincodes"].is_array()) {
    throw HttpError(400, R"(expected {"pincodes": ["110001", …], "size": "a6", "plan": "…"})");
  }
  const json& pins = body["pincodes"];
  if (pins.empty()) throw HttpError(400, "'pincodes' is empty");
  if (pins.size() > context.max_batch) {
    throw HttpError(413, "at most " + std::to_string(context.max_batch) +
                             " labels per request, got " + std::to_string(pins.size()));
  }
  // The body's size and plan, else the query's, else the defaults.
  const auto text = [&](const char* key) -> std::optional<std::string> {
    if (!body.contains(key)) return std::nullopt;
    if (!body[key].is_string()) throw HttpError(400, std::string("'") + key + "' must be a string");
    return body[key].get<std::string>();
  };
  LabelOptions options;
  const std::optional<std::string> size = text("size");
  options.size = size ? LabelSizeValue(*size) : LabelSizeQuery(request);
  const std::optional<std::string> plan_name = text("plan");
  const std::string plan = plan_name ? PlanNameValue(*plan_name) : PlanQuery(request);
  std::vector<Pincode> pincodes;
  pincodes.reserve(pins.size());
  for (std::size_t i = 0; i < pins.size(); ++i) {
    pincodes.push_back(PincodeValue(pins[i], "pincodes[" + std::to_string(i) + "]"));
  }

  std::vector<LabelContent> labels;
  labels.reserve(pincodes.size());
  {
    auto connection = context.pool->acquire();
    const db::SortPlan sort_plan = LoadPlan(*connection, plan);
    for (const Pincode pincode : pincodes) {
      labels.push_back(LabelFor(LoadActivePincode(*connection, pincode), sort_plan));
    }
  }
  return Rendered(RenderLabelsPdf(labels, options), context, "application/pdf", "labels.pdf",
                  labels.size());
}

}  // namespace pintag::app
