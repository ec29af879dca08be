// The text parsers every route shares: pincodes, tag keys, label sizes, sort plan names, dpi and
// integer query parameters. Each must accept or refuse (a 400 HttpError), never crash; what it
// accepts must print back to text it accepts again as the same value.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "app/params.hpp"
#include "pintag/codec/label_size.hpp"
#include "pintag/codec/pincode.hpp"
#include "pintag/codec/tag_key.hpp"
#include "pintag/server/problem.hpp"

namespace {

template <typename Parse>
void Refusable(Parse parse) {
  try {
    parse();
  } catch (const pintag::server::HttpError& error) {
    if (error.problem().status != 400) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);

  if (const auto pincode = pintag::ParsePincode(text)) {
    const auto again = pintag::ParsePincode(pincode.pincode->str());
    if (!again || again.pincode->value() != pincode.pincode->value()) std::abort();
  }
  if (const auto key = pintag::ParseTagKey(text)) {
    const auto again = pintag::ParseTagKey(std::to_string(key.key->value()));
    if (!again || again.key->value() != key.key->value()) std::abort();
  }
  if (const auto label = pintag::ParseLabelSize(text)) {
    const auto again = pintag::ParseLabelSize(pintag::ToString(*label.size));
    const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-5 * std::abs(b); };
    if (!again || !near(again.size->width_mm, label.size->width_mm) ||
        !near(again.size->height_mm, label.size->height_mm)) {
      std::abort();
    }
  }
  Refusable([&] { (void)pintag::app::PlanNameValue(text); });
  Refusable([&] { (void)pintag::app::LabelSizeValue(text); });
  Refusable([&] { (void)pintag::app::PincodeValue(nlohmann::json(std::string(text)), "fuzz"); });

  pintag::server::HttpRequest request;
  for (const char* name : {"dpi", "plan", "size", "limit", "px"}) request.query.emplace(name, text);
  request.path_params = {{"pin", std::string(text)},
                         {"key", std::string(text)},
                         {"id", std::string(text)},
                         {"name", std::string(text)}};
  Refusable([&] { (void)pintag::app::DpiQuery(request); });
  Refusable([&] { (void)pintag::app::PlanQuery(request); });
  Refusable([&] { (void)pintag::app::LabelSizeQuery(request); });
  Refusable([&] { (void)pintag::app::IntegerQuery(request, "limit", 20, 1, 1000); });
  Refusable([&] { (void)pintag::app::NumberQuery(request, "px", 1, 4096); });
  Refusable([&] { (void)pintag::app::PincodeParam(request); });
  Refusable([&] { (void)pintag::app::KeyParam(request); });
  Refusable([&] { (void)pintag::app::TokenIdParam(request); });
  return 0;
}
