#include "pintag/server/label_routes.hpp"

#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "pintag/codec/png_io.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/codec/tag_svg.hpp"

namespace pintag::server {
namespace {

constexpr std::size_t kMaxPlanName = 100;

// A query number within [min, max], or the default when absent; HttpError 400 otherwise.
double NumberParam(const HttpRequest& request, std::string_view name, double fallback, double min,
                   double max) {
  const std::optional<std::string> text = request.queryParam(name);
  if (!text) return fallback;
  double value = 0;
  const auto [end, ec] = std::from_chars(text->data(), text->data() + text->size(), value);
  if (ec != std::errc() || end != text->data() + text->size() || !std::isfinite(value) ||
      value < min || value > max) {
    char range[64];
    std::snprintf(range, sizeof range, "%g to %g", min, max);
    throw HttpError(400, "query parameter '" + std::string(name) + "' must be a number from " +
                             range + ", got '" + text->substr(0, 40) + "'");
  }
  return value;
}

Pincode PincodeParam(const std::string& text) {
  const ParsedPincode parsed = ParsePincode(text);
  if (!parsed) throw HttpError(400, parsed.error, "Malformed Pincode");
  return *parsed.pincode;
}

std::optional<std::string> PlanParam(const std::optional<std::string>& plan) {
  if (!plan || plan->empty()) return std::nullopt;
  if (plan->size() > kMaxPlanName) throw HttpError(400, "plan name is too long");
  return plan;
}

LabelOptions LabelOptionsFrom(const HttpRequest& request) {
  LabelOptions options;
  if (const auto size = request.queryParam("size")) {
    const ParsedLabelSize parsed = ParseLabelSize(*size);
    if (!parsed) throw HttpError(400, parsed.error, "Bad Label Size");
    options.size = *parsed.size;
  }
  options.dpi = NumberParam(request, "dpi", 300, kMinLabelDpi, kMaxLabelDpi);
  return options;
}

class LabelService {
 public:
  LabelService(LabelContentProvider provider, std::shared_ptr<Metrics> metrics,
               LabelRouteOptions options)
      : provider_(std::move(provider)), metrics_(std::move(metrics)), options_(options) {
    metrics_->defineCounter(kLabelsRenderedCounter, "Labels rendered (PDF pages, PNGs, SVGs).");
    metrics_->defineCounter(kTagsRenderedCounter, "Tag images rendered.");
  }

  LabelContent lookup(Pincode pincode, const std::optional<std::string>& plan) const {
    if (!provider_) throw HttpError(503, "labels are not available: no registry is connected");
    LabelLookup found = provider_(pincode, plan);
    if (found.problem) throw HttpError(*found.problem);
    if (!found.label) throw HttpError(404, "pincode " + pincode.str() + " is not in the registry");
    return std::move(*found.label);
  }

  HttpResponse tagPng(const HttpRequest& request) const {
    const LabelContent label = lookup(PincodeParam(request.pathParam("pin")), std::nullopt);
    const int px =
        static_cast<int>(NumberParam(request, "px", 256, kMinTagSquarePx, options_.max_tag_px));
    const double dpi = NumberParam(request, "dpi", 300, kMinLabelDpi, kMaxLabelDpi);
    const TagRaster raster = RenderTagRaster(label.key, {px, 4});
    std::string error;
    const std::vector<std::uint8_t> png = EncodePng(raster.image, dpi, &error);
    if (!error.empty()) throw std::runtime_error(error);
    metrics_->increment(kTagsRenderedCounter);
    return Named(HttpResponse::Bytes("image/png", png), "tag-" + label.pincode.str() + ".png");
  }

  HttpResponse tagSvg(const HttpRequest& request) const {
    const LabelContent label = lookup(PincodeParam(request.pathParam("pin")), std::nullopt);
    if (request.queryParam("mm") && request.queryParam("px")) {
      throw HttpError(400, "give at most one of 'mm' and 'px'");
    }
    const TagSvgOptions svg =
        request.queryParam("px")
            ? TagSvgOptions{NumberParam(request, "px", 256, kMinTagSquarePx, options_.max_tag_px),
                            "px"}
            : TagSvgOptions{NumberParam(request, "mm", 50, 5, 500), "mm"};
    metrics_->increment(kTagsRenderedCounter);
    return Named(HttpResponse::Bytes("image/svg+xml", RenderTagSvg(label.key, svg)),
                 "tag-" + label.pincode.str() + ".svg");
  }

  HttpResponse label(const HttpRequest& request, std::string_view format) const {
    const LabelOptions options = LabelOptionsFrom(request);
    const LabelContent label =
        lookup(PincodeParam(request.pathParam("pin")), PlanParam(request.queryParam("plan")));
    RenderedLabel rendered;
    std::string type;
    if (format == "pdf") {
      rendered = RenderLabelPdf(label, options);
      type = "application/pdf";
    } else if (format == "png") {
      rendered = RenderLabelPng(label, options);
      type = "image/png";
    } else {
      rendered = RenderLabelSvg(label, options);
      type = "image/svg+xml";
    }
    if (!rendered) throw HttpError(400, rendered.error, "Cannot Render Label");
    metrics_->increment(kLabelsRenderedCounter);
    return Named(HttpResponse::Bytes(type, rendered.bytes),
                 "label-" + label.pincode.str() + "." + std::string(format));
  }

  HttpResponse batch(const HttpRequest& request) const {
    nlohmann::json body = nlohmann::json::parse(request.body, nullptr, false);
    if (body.is_discarded()) throw HttpError(400, "the body is not valid JSON");
    if (body.is_array()) body = nlohmann::json{{"pincodes", body}};
    if (!body.is_object() || !body.contains("pincodes") || !body["pincodes"].is_array()) {
      throw HttpError(400, R"(expected {"pincodes": ["110001", …], "size": "a6", "plan": "…"})");
    }
    const nlohmann::json& pins = body["pincodes"];
    if (pins.empty()) throw HttpError(400, "'pincodes' is empty");
    if (pins.size() > options_.max_batch) {
      throw HttpError(413, "at most " + std::to_string(options_.max_batch) +
                               " labels per request, got " + std::to_string(pins.size()));
    }
    HttpRequest with_query = request;
    for (const char* key : {"size", "plan"}) {
      if (body.contains(key)) {
        if (!body[key].is_string())
          throw HttpError(400, std::string("'") + key + "' must be a string");
        with_query.query.erase(key);
        with_query.query.emplace(key, body[key].get<std::string>());
      }
    }
    const LabelOptions options = LabelOptionsFrom(with_query);
    const std::optional<std::string> plan = PlanParam(with_query.queryParam("plan"));
    std::vector<LabelContent> labels;
    labels.reserve(pins.size());
    for (std::size_t i = 0; i < pins.size(); ++i) {
      const nlohmann::json& pin = pins[i];
      std::string text;
      if (pin.is_string()) {
        text = pin.get<std::string>();
      } else if (pin.is_number_unsigned()) {
        text = std::to_string(pin.get<std::uint64_t>());
      } else {
        throw HttpError(400, "pincodes[" + std::to_string(i) + "] must be a string of six digits");
      }
      const ParsedPincode parsed = ParsePincode(text);
      if (!parsed) {
        throw HttpError(400, "pincodes[" + std::to_string(i) + "]: " + parsed.error,
                        "Malformed Pincode");
      }
      labels.push_back(lookup(*parsed.pincode, plan));
    }
    const RenderedLabel rendered = RenderLabelsPdf(labels, options);
    if (!rendered) throw HttpError(400, rendered.error, "Cannot Render Label");
    metrics_->increment(kLabelsRenderedCounter, static_cast<double>(labels.size()));
    return Named(HttpResponse::Bytes("application/pdf", rendered.bytes), "labels.pdf");
  }

 private:
  static HttpResponse Named(HttpResponse response, const std::string& filename) {
    response.headers.emplace_back("Content-Disposition", "inline; filename=\"" + filename + "\"");
    response.headers.emplace_back("Cache-Control", "no-cache");
    return response;
  }

  LabelContentProvider provider_;
  std::shared_ptr<Metrics> metrics_;
  LabelRouteOptions options_;
};

}  // namespace

void AddLabelRoutes(Router& router, LabelContentProvider provider, std::shared_ptr<Metrics> metrics,
                    LabelRouteOptions options) {
  auto service = std::make_shared<LabelService>(std::move(provider), std::move(metrics), options);
  const QueryParamDoc size{"size", "label size: 100x150mm (default), a6, 4x6in or WxH mm|cm|in"};
  const QueryParamDoc dpi{"dpi", "PNG resolution, 72 to 1200 (default 300), recorded in the file",
                          "number"};
  const QueryParamDoc plan{"plan", "sort plan whose bin is printed"};
  const auto label_route = [&](const std::string& format, std::string type,
                               std::vector<QueryParamDoc> query) {
    Route route = MakeRoute(
        "GET", "/api/v1/labels/{pin}." + format, Access::kCounter,
        [service, format](const HttpRequest& r) { return service->label(r, format); },
        "Printable label for a pincode (" + format + ")", "labels");
    route.produces = {std::move(type)};
    route.query = std::move(query);
    router.add(std::move(route));
  };
  Route tag_png = MakeRoute(
      "GET", "/api/v1/tags/{pin}.png", Access::kCounter,
      [service](const HttpRequest& r) { return service->tagPng(r); },
      "The pincode's PinTag as a PNG (quiet zone included)", "labels");
  tag_png.produces = {"image/png"};
  tag_png.query = {{"px", "black square side in pixels, 64 to max (default 256)", "integer"}, dpi};
  router.add(std::move(tag_png));
  Route tag_svg = MakeRoute(
      "GET", "/api/v1/tags/{pin}.svg", Access::kCounter,
      [service](const HttpRequest& r) { return service->tagSvg(r); },
      "The pincode's PinTag as SVG (quiet zone included)", "labels");
  tag_svg.produces = {"image/svg+xml"};
  tag_svg.query = {{"mm", "black square side in millimetres, 5 to 500 (default 50)", "number"},
                   {"px", "black square side in pixels instead of mm", "number"}};
  router.add(std::move(tag_svg));
  label_route("pdf", "application/pdf", {size, plan});
  label_route("png", "image/png", {size, dpi, plan});
  label_route("svg", "image/svg+xml", {size, plan});
  Route batch = MakeRoute(
      "POST", "/api/v1/labels", Access::kCounter,
      [service](const HttpRequest& r) { return service->batch(r); },
      R"(Many labels as one PDF, a page each; body {"pincodes": [...], "size": "a6", "plan": "..."})",
      "labels");
  batch.produces = {"application/pdf"};
  batch.consumes = {"application/json"};
  router.add(std::move(batch));
}

}  // namespace pintag::server
