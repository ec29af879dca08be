#include "cli_values.hpp"

#include <charconv>
#include <cstdio>
#include <cstdlib>

namespace pintag::bench {

std::optional<scene::World> ParseWorld(std::string_view text) {
  if (text == "held-out") return scene::World::kHeldOut;
  if (text == "tuning") return scene::World::kTuning;
  if (text == "blind") return scene::World::kBlind;
  return std::nullopt;
}

std::optional<std::uint64_t> ParseSeed(std::string_view text) {
  if (text.empty() || text.size() > 19) return std::nullopt;
  std::uint64_t seed = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), seed);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return seed;
}

scene::World WorldOrExit(const char* tool, const char* text) {
  const std::optional<scene::World> world = ParseWorld(text);
  if (world) return *world;
  std::fprintf(stderr, "%s: --world is held-out, tuning or blind, got \"%s\"\n", tool, text);
  std::exit(2);
}

std::uint64_t SeedOrExit(const char* tool, const char* text) {
  const std::optional<std::uint64_t> seed = ParseSeed(text);
  if (seed) return *seed;
  std::fprintf(stderr, "%s: --seed takes a whole number, got \"%s\"\n", tool, text);
  std::exit(2);
}

int IntegerOrExit(const char* tool, const char* option, const char* text, int lowest, int highest) {
  const std::string_view view(text);
  int value = 0;
  const auto [end, error] = std::from_chars(view.data(), view.data() + view.size(), value);
  if (view.empty() || error != std::errc() || end != view.data() + view.size() || value < lowest ||
      value > highest) {
    std::fprintf(stderr, "%s: %s takes a whole number from %d to %d, got \"%s\"\n", tool, option,
                 lowest, highest, text);
    std::exit(2);
  }
  return value;
}

double NumberOrExit(const char* tool, const char* option, const char* text, double lowest,
                    double highest) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  // Written so that NaN fails the range test too.
  if (*text == '\0' || *end != '\0' || !(value >= lowest && value <= highest)) {
    std::fprintf(stderr, "%s: %s takes a number from %g to %g, got \"%s\"\n", tool, option, lowest,
                 highest, text);
    std::exit(2);
  }
  return value;
}

}  // namespace pintag::bench
