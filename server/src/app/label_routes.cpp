// Tag and label routes: a pincode's PinTag alone (PNG, SVG) and its printable label (PDF, PNG,
// SVG; many as one PDF). Labels print the bin of the asked sort plan, the default plan when none
// is asked for. Unknown pincodes are 404, retired ones 410.

#include <algorithm>
#include <cctype>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "app/db_problems.hpp"
#include "app/params.hpp"
#include "app/registry_json.hpp"
#include "app/routes.hpp"
#include "pintag/codec/label.hpp"
#include "pintag/codec/png_io.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/codec/tag_svg.hpp"
#include "pintag/db/text.hpp"

namespace pintag::app {
namespace {

constexpr double kDefaultTagMm = 50;
constexpr double kMinTagMm = 5;
constexpr double kMaxTagMm = 500;

/// Names as a clerk types them: ASCII case and spaces at either end do not count (a clerk's
/// stray space; and offices added through the API keep their names as sent).
bool SameName(std::string_view a, std::string_view b) {
  a = db::TrimSpaces(a);
  b = db::TrimSpaces(b);
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

/// The office a label prints: the one named (a pincode can serve a dozen offices, and the
/// addressee's is the one a person reads), else the main one.
const db::PostOffice* ChosenOffice(const db::PincodeRecord& record,
                                   const std::optional<std::string>& name) {
  if (!name || db::TrimSpaces(*name).empty()) return db::MainOffice(record);
  // The office of exactly that name first: two offices may differ only in case ("Twin", "TWIN").
  for (const db::PostOffice& office : record.offices) {
    if (office.name == *name) return &office;
  }
  for (const db::PostOffice& office : record.offices) {
    if (SameName(office.name, *name)) return &office;
  }
  std::string known;
  for (std::size_t i = 0; i < record.offices.size() && i < 5; ++i) {
    known += (i == 0 ? "" : ", ") + record.offices[i].name;
  }
  if (record.offices.size() > 5) {
    known += " and " + std::to_string(record.offices.size() - 5) + " more";
  }
  throw HttpError(400,
                  "pincode " + record.pincode.str() + " has no office named '" +
                      name->substr(0, 80) + "'" + (known.empty() ? "" : "; its offices: " + known),
                  "Unknown Office");
}

// What a label prints for an active pincode going to `bin` of the plan `plan_name`, naming
// `office` or the main one.
LabelContent LabelFor(const db::PincodeRecord& record, std::string plan_name, std::string bin,
                      const std::optional<std::string>& office_name = std::nullopt) {
  LabelContent label;
  label.pincode = record.pincode;
  label.key = record.key;
  // The place printed under the office is that office's: a pincode's offices can lie in
  // several districts (1,269 of the seed's pincodes), and the one asked for need not be the main
  // one the record's summary comes from. A pincode without offices prints none.
  if (const db::PostOffice* office = ChosenOffice(record, office_name)) {
    label.office = office->name;
    label.district = office->district;
    label.state = office->state;
  }
  label.plan = std::move(plan_name);
  label.bin = std::move(bin);
  return label;
}

HttpResponse Named(HttpResponse response, const std::string& filename) {
  response.headers.emplace_back("Content-Disposition", "inline; filename=\"" + filename + "\"");
  response.headers.emplace_back("Cache-Control", "no-cache");
  return response;
}

HttpResponse Rendered(const RenderedLabel& rendered, const AppContext& context, std::string type,
                      const std::string& filename, std::size_t labels = 1) {
  // The label's content or options are the request's to fix; the renderer failing is ours.
  if (!rendered && rendered.internal_error) {
    throw HttpError(500, rendered.error, "Label Rendering Failed");
  }
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
  std::string bin = RouteUnder(*connection, pincode, plan_name).bin;
  label.content = LabelFor(record, plan_name, std::move(bin), request.queryParam("office"));
  return label;
}

TagKey ActiveKey(const AppContext& context, const HttpRequest& request) {
  const Pincode pincode = PincodeParam(request);
  auto connection = context.pool->acquire();
  return LoadActivePincode(*connection, pincode).key;
}

}  // namespace

int DefaultTagPx(const AppContext& context) {
  constexpr int kDefaultTagPx = 256;
  return std::min(kDefaultTagPx, context.max_tag_px);
}

HttpResponse GetTagPng(const AppContext& context, const HttpRequest& request) {
  // A server whose --max-tag-px is under the default renders its largest by default: the default
  // is not a size the server would refuse if it were asked for.
  const long long px =
      IntegerQuery(request, "px", DefaultTagPx(context), kMinTagSquarePx, context.max_tag_px);
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
  // A misspelt "plan" must not print the default plan's bins unnoticed.
  if (const std::optional<std::string> field = UnknownField(body, {"pincodes", "size", "plan"})) {
    throw HttpError(400, "unknown field '" + field->substr(0, 40) +
                             "'; a batch takes 'pincodes', 'size' and 'plan'");
  }
  const json& pins = body["pincodes"];
  if (pins.empty()) throw HttpError(400, "'pincodes' is empty");
  if (pins.size() > context.max_batch) {
    // The limit as a number too, so that a client (the counter page) can split the batch by it.
    server::Problem problem{413, "Content Too Large",
                            "at most " + std::to_string(context.max_batch) +
                                " labels per request, got " + std::to_string(pins.size())};
    problem.numbers = {{"max_batch", static_cast<std::int64_t>(context.max_batch)}};
    throw HttpError(std::move(problem));
  }
  // The body's size and plan, else the query's, else the defaults. null is leaving it out, as for
  // an item's "office" and every optional field of every body.
  const auto text = [&](const char* key) -> std::optional<std::string> {
    if (!body.contains(key) || body[key].is_null()) return std::nullopt;
    if (!body[key].is_string()) {
      throw HttpError(400, std::string("'") + key + "' must be a string or null");
    }
    return body[key].get<std::string>();
  };
  // Given in both places, they must agree: which one printed would be a guess the clerk never
  // sees (a body's "plan" won over ?plan= silently). Sizes are compared as sizes ("A6" is "a6").
  const auto given_twice = [&](const char* key, const std::string& in_body) {
    return HttpError(400, std::string("'") + key + "' is given twice: " + Quoted(in_body) +
                              " in the body and " + Quoted(*request.queryParam(key)) +
                              " in the query; give it once");
  };
  LabelOptions options;
  const std::optional<std::string> size = text("size");
  options.size = size ? LabelSizeValue(*size) : LabelSizeQuery(request);
  if (size && request.queryParam("size") && LabelSizeQuery(request) != options.size) {
    throw given_twice("size", *size);
  }
  const std::optional<std::string> plan_name = text("plan");
  const std::string plan = plan_name ? PlanNameValue(*plan_name) : PlanQuery(request);
  if (plan_name && request.queryParam("plan") && PlanQuery(request) != plan) {
    throw given_twice("plan", *plan_name);
  }
  // Each item is a pincode, or {"pincode": …, "office": …} to print that office's name.
  struct Item {
    Pincode pincode;
    std::optional<std::string> office;
  };
  std::vector<Item> items;
  items.reserve(pins.size());
  for (std::size_t i = 0; i < pins.size(); ++i) {
    const std::string where = "pincodes[" + std::to_string(i) + "]";
    if (!pins[i].is_object()) {
      items.push_back({PincodeValue(pins[i], where), std::nullopt});
      continue;
    }
    if (const std::optional<std::string> field = UnknownField(pins[i], {"pincode", "office"})) {
      throw HttpError(400, where + " has an unknown field '" + field->substr(0, 40) +
                               "'; an item is a pincode or {\"pincode\", \"office\"}");
    }
    if (!pins[i].contains("pincode")) throw HttpError(400, where + " needs a 'pincode'");
    Item item{PincodeValue(pins[i]["pincode"], where + ".pincode"), std::nullopt};
    // "office": null is the same as leaving it out: the pincode's main office.
    if (pins[i].contains("office") && !pins[i]["office"].is_null()) {
      if (!pins[i]["office"].is_string()) {
        throw HttpError(400, where + ".office must be a string or null");
      }
      item.office = pins[i]["office"].get<std::string>();
    }
    items.push_back(std::move(item));
  }

  std::vector<LabelContent> labels;
  labels.reserve(items.size());
  {
    auto connection = context.pool->acquire();
    // Read whole once, so every label of the batch comes from one version of the plan.
    const db::SortPlan sort_plan = LoadPlan(*connection, plan);
    for (std::size_t i = 0; i < items.size(); ++i) {
      try {
        labels.push_back(LabelFor(LoadActivePincode(*connection, items[i].pincode), sort_plan.name,
                                  db::RouteWith(sort_plan, items[i].pincode).bin, items[i].office));
      } catch (const HttpError& e) {
        // Which item of the batch, so a clerk finds the line to fix; a server fault is not
        // the item's.
        server::Problem problem = e.problem();
        if (problem.status < 500) {
          problem.detail = "pincodes[" + std::to_string(i) + "]: " + problem.detail;
        }
        throw HttpError(std::move(problem));
      }
    }
  }
  RenderedLabel rendered = RenderLabelsPdf(labels, options);
  if (rendered.refused_label) {
    // Named as an item's other problems are, so a clerk finds the line to fix.
    rendered.error = "pincodes[" + std::to_string(*rendered.refused_label) + "]: " + rendered.error;
  }
  return Rendered(rendered, context, "application/pdf", "labels.pdf", labels.size());
}

}  // namespace pintag::app
