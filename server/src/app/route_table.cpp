#include "app/route_table.hpp"

#include <string>
#include <vector>

#include "app/params.hpp"
#include "app/routes.hpp"

namespace pintag::app {
namespace {

using server::Access;
using server::HeaderDoc;
using server::QueryParamDoc;

/// The headers of a sort plan's conditional requests (docs/API.md, "Sort plans").
HeaderDoc PlanIfMatchDoc() {
  return {"If-Match", "the plan's ETag as read: only if the plan is unchanged since (else 412)"};
}
HeaderDoc PlanIfNoneMatchDoc(bool put) {
  return {"If-None-Match", put ? "*: only if no plan has this name (else 412)"
                               : "the ETag held: 304 with no body while the plan is unchanged"};
}
HeaderDoc PlanETagDoc() {
  return {"ETag",
          "the plan's version (JSON and CSV forms differ: \"…-csv\"); send it back in "
          "If-Match to change only this version"};
}

/// What /openapi.json says about a route beyond its method, path and role.
struct RouteDoc {
  const char* tag = "api";                 ///< OpenAPI tag: the group in the route list
  std::string summary;                     ///< one line
  std::vector<QueryParamDoc> query = {};   ///< documented query parameters
  std::vector<std::string> consumes = {};  ///< request body media types; none: no body
  std::vector<std::string> produces = {};  ///< success media types; none: application/json
  std::vector<int> success = {200};        ///< the statuses a success answers with
  std::vector<server::HeaderDoc> request_headers = {};   ///< headers it reads (If-Match, …)
  std::vector<server::HeaderDoc> response_headers = {};  ///< headers its successes carry
};

/// One row of the table.
struct AppRoute {
  const char* method = "GET";
  const char* path = "/";
  Access role = Access::kAdmin;
  RouteHandler handler = nullptr;
  RouteDoc doc;
  std::vector<int> routine_statuses = {};  ///< answers whose access lines are throttled
};

/// A handler that writes the database: it runs holding a write gate permit (WriteGate), or the
/// request is answered 503 Writers Busy when the writers inside have been stuck for a second.
template <RouteHandler kHandler>
HttpResponse Writing(const AppContext& context, const HttpRequest& request) {
  const WriteGate::Permit permit = context.write_gate->enter();
  return kHandler(context, request);
}

}  // namespace

server::Router AppRouter(const std::shared_ptr<const AppContext>& context) {
  const std::string max_tag_px = std::to_string(context->max_tag_px);
  const std::string default_tag_px = std::to_string(DefaultTagPx(*context));
  const std::vector<std::string> photo_types = {"image/jpeg",          "image/png",
                                                "image/tiff",          "image/webp",
                                                "multipart/form-data", "application/octet-stream"};
  // clang-format off
  const AppRoute table[] = {
  // method    path                                 role              handler
    {"GET",    "/api/v1/pincodes/{pin}",            Access::kOpen,    GetPincode,
     {"registry", "A pincode: key, status, district, state, circle, region, division and every post office"}},
    {"GET",    "/api/v1/pincodes",                  Access::kOpen,    SearchPincodes,
     {"registry", "Search post offices by name prefix, district and/or state",
      {{"q", "office name prefix (case-insensitive for ASCII)"},
       {"district", "district, exact (case-insensitive for ASCII)"},
       {"state", "state, exact (case-insensitive for ASCII)"},
       {"limit", "page size, 1 to 500 (default 50)", "integer"},
       {"offset", "rows to skip (default 0)", "integer"}}}},
    {"GET",    "/api/v1/keys/{key}",                Access::kOpen,    GetKey,
     {"registry", "The pincode a tag key belongs to (retired ones included)"}},
    {"POST",   "/api/v1/pincodes",                  Access::kAdmin,   Writing<PostPincode>,
     {"registry", "Add a pincode (and its offices); answers 201 with the allocated key", {},
      {"application/json"}, {}, {201}, {},
      {{"Location", "the new pincode's URL (/api/v1/pincodes/{pin})"}}}},
    {"POST",   "/api/v1/pincodes/{pin}/retire",     Access::kAdmin,   Writing<PostRetirePincode>,
     {"registry", "Retire a pincode: it keeps its key, labels are no longer issued"}},

    {"GET",    "/api/v1/tags/{pin}.png",            Access::kCounter, GetTagPng,
     {"labels", "The pincode's PinTag as a PNG (quiet zone included)",
      {{"px", "black square side in pixels, 64 to " + max_tag_px + " (default " + default_tag_px + ")", "integer"},
       DpiQueryDoc()},
      {}, {"image/png"}}},
    {"GET",    "/api/v1/tags/{pin}.svg",            Access::kCounter, GetTagSvg,
     {"labels", "The pincode's PinTag as SVG (quiet zone included)",
      {{"mm", "black square side in millimetres, 5 to 500 (default 50)", "number"},
       {"px", "black square side in pixels instead of mm, 64 to " + max_tag_px, "number"}},
      {}, {"image/svg+xml"}}},
    {"GET",    "/api/v1/labels/{pin}.pdf",          Access::kCounter, GetLabelPdf,
     {"labels", "Printable label for a pincode (pdf) with its bin under the sort plan",
      {LabelSizeQueryDoc(), PlanQueryDoc(), OfficeQueryDoc()}, {}, {"application/pdf"}}},
    {"GET",    "/api/v1/labels/{pin}.png",          Access::kCounter, GetLabelPng,
     {"labels", "Printable label for a pincode (png) with its bin under the sort plan",
      {LabelSizeQueryDoc(), DpiQueryDoc(), PlanQueryDoc(), OfficeQueryDoc()}, {}, {"image/png"}}},
    {"GET",    "/api/v1/labels/{pin}.svg",          Access::kCounter, GetLabelSvg,
     {"labels", "Printable label for a pincode (svg) with its bin under the sort plan",
      {LabelSizeQueryDoc(), PlanQueryDoc(), OfficeQueryDoc()}, {}, {"image/svg+xml"}}},
    {"POST",   "/api/v1/labels",                    Access::kCounter, PostLabels,
     {"labels", R"(Many labels as one PDF, a page each; body {"pincodes": [...], "size": "a6", "plan": "..."}, an item a pincode or {"pincode": "...", "office": "..."}; size and plan may be query parameters instead)",
      {LabelSizeQueryDoc(), PlanQueryDoc()}, {"application/json"}, {"application/pdf"}}},

    {"POST",   "/api/v1/detect",                    Access::kScanner, PostDetect,
     {"detection", "Find every PinTag in a photo: pincode, key, status, office, bin, corners, pose",
      {PlanQueryDoc(),
       {"tag_size_mm", "black square side, millimetres (default: the tag of a 100x150mm label, 57.892; a6 57.062, 4x6in 58.889)", "number"},
       {"fx", "focal length x, pixels (with fy: intrinsics given)", "number"},
       {"fy", "focal length y, pixels", "number"},
       {"cx", "principal point x, pixels (default: image centre)", "number"},
       {"cy", "principal point y, pixels (default: image centre)", "number"},
       {"overlay", "1: answer the photo with the tags outlined, as PNG; inline: the JSON with that PNG as a data URL in \"overlay\""}},
      photo_types, {"application/json", "image/png"}}},

    {"GET",    "/api/v1/route/{pin}",               Access::kOpen,    GetRoute,
     {"routing", "The bin for a pincode under a sort plan (longest prefix wins)", {PlanQueryDoc()}}},
    {"GET",    "/api/v1/sortplans",                 Access::kOpen,    GetSortPlans,
     {"routing", "Every sort plan with its fallback bin and rule count"}},
    {"GET",    "/api/v1/sortplans/{name}",          Access::kOpen,    GetSortPlan,
     {"routing", "A sort plan's rules as JSON, or CSV (?format=csv or Accept: text/csv), with its version as ETag",
      {{"format", "json (default) or csv"}}, {}, {"application/json", "text/csv"}, {200, 304},
      {PlanIfNoneMatchDoc(false)}, {PlanETagDoc()}}},
    {"PUT",    "/api/v1/sortplans/{name}",          Access::kAdmin,   Writing<PutSortPlan>,
     {"routing", "Create or replace a sort plan from CSV (prefix,bin with one * row) or JSON; with If-Match: its ETag, only if unchanged since read (else 412), with If-None-Match: *, only if new; a new name that reads like a stored plan's but differs in Unicode code points is 409",
      {{"description", "plan description (CSV bodies)"}}, {"text/csv", "application/json"}, {},
      {200, 201}, {PlanIfMatchDoc(), PlanIfNoneMatchDoc(true)}, {PlanETagDoc()}}},
    {"DELETE", "/api/v1/sortplans/{name}",          Access::kAdmin,   Writing<DeleteSortPlan>,
     {"routing", "Delete a sort plan (not the default one, 409) and answer it as it was; with If-Match: its ETag, only if unchanged since read (else 412)",
      {}, {}, {}, {200}, {PlanIfMatchDoc()}, {PlanETagDoc()}}},

    {"GET",    "/api/v1/registry",                  Access::kOpen,    GetRegistryStatus,
     {"replication", "Which registry version this server serves, and whether it is the primary or a replica"}},
    {"GET",    "/api/v1/registry/snapshot",         Access::kReplica, GetRegistrySnapshot,
     {"replication", "The registry as an SQLite snapshot for read-only replicas (ETag: its registry version and the primary run)",
      {}, {}, {"application/vnd.sqlite3"}, {200, 304},
      {{"If-None-Match", "the ETag of the snapshot held: 304 with no body while it is current"}},
      {{"ETag", "the registry version and the primary's run (\"<version>-<epoch>\")"}}},
     {304}},  // a replica's poll, once a second, with nothing new: one access line a minute

    {"POST",   "/api/v1/tokens",                    Access::kAdmin,   Writing<PostToken>,
     {"tokens", R"(Create a token {"role", "label"}; the answer holds its secret, once)", {},
      {"application/json"}, {}, {201}}},
    {"GET",    "/api/v1/tokens",                    Access::kAdmin,   GetTokens,
     {"tokens", "Every token (never a secret), revoked ones included"}},
    {"DELETE", "/api/v1/tokens/{id}",               Access::kAdmin,   Writing<RevokeToken>,
     {"tokens", "Revoke a token (permanent)"}},
    {"POST",   "/api/v1/tokens/{id}/revoke",        Access::kAdmin,   Writing<RevokeToken>,
     {"tokens", "Revoke a token (same as DELETE)"}},
  };
  // clang-format on

  server::Router router;
  for (const AppRoute& row : table) {
    server::Route route = server::MakeRoute(
        row.method, row.path, row.role,
        [context, handler = row.handler](const HttpRequest& request) {
          return handler(*context, request);
        },
        row.doc.summary, row.doc.tag);
    route.query = row.doc.query;
    route.consumes = row.doc.consumes;
    route.produces = row.doc.produces;
    route.success = row.doc.success;
    route.request_headers = row.doc.request_headers;
    route.response_headers = row.doc.response_headers;
    route.routine_statuses = row.routine_statuses;
    router.add(std::move(route));
  }
  return router;
}

}  // namespace pintag::app
