#include "cli_values.hpp"

#include <charconv>

namespace pintag::bench {

std::optional<scene::World> ParseWorld(std::string_view text) {
  if (text == "held-out") return scene::World::kHeldOut;
  if (text == "tuning") return scene::World::kTuning;
  return std::nullopt;
}

std::optional<std::uint64_t> ParseSeed(std::string_view text) {
  if (text.empty() || text.size() > 19) return std::nullopt;
  std::uint64_t seed = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), seed);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return seed;
}

}  // namespace pintag::bench
