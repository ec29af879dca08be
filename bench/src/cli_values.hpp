#pragma once
// Values the benchmark and the research probes take on their command lines, read strictly: a
// typo in --world ran the held-out world, which nothing may be tuned on, and --seed abc ran seed 0.

#include <cstdint>
#include <optional>
#include <string_view>

#include "pintag/scene/scene.hpp"

namespace pintag::bench {

/// "held-out" or "tuning"; nothing for anything else.
std::optional<scene::World> ParseWorld(std::string_view text);

/// A decimal seed of at most 19 digits (no sign, nothing after it); nothing for anything else.
std::optional<std::uint64_t> ParseSeed(std::string_view text);

/// ParseWorld and ParseSeed for a tool's option: anything else is printed as `tool`'s usage
/// error and the process exits with status 2.
scene::World WorldOrExit(const char* tool, const char* text);
std::uint64_t SeedOrExit(const char* tool, const char* text);

/// The whole of `text` as a decimal integer in [lowest, highest], or a number in [lowest,
/// highest]; anything else (a count of "abc" read as 0, a negative count clamped to 1) is
/// printed as `tool`'s usage error naming `option`, and the process exits with status 2.
int IntegerOrExit(const char* tool, const char* option, const char* text, int lowest, int highest);
double NumberOrExit(const char* tool, const char* option, const char* text, double lowest,
                    double highest);

}  // namespace pintag::bench
