#include "reading/region_system.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>

namespace pintag::reading {
namespace {

// A spatial hash of an image pixel: picking pixels by it thins them evenly, without the rows or
// columns a linear rule such as x + 3 y would pick for some strides.
std::uint32_t PositionHash(int x, int y) {
  std::uint32_t h =
      static_cast<std::uint32_t>(x) * 73856093U ^ static_cast<std::uint32_t>(y) * 19349663U;
  h ^= h >> 13;
  h *= 0x5bd1e995U;
  return h ^ (h >> 15);
}

template <int kChannels>
void AddSample(RegionSystem<kChannels>& system, const SampleWeights& w,
               const std::array<double, kChannels>& values, double weight = 1) {
  const std::vector<int>& touched = w.touched;
  for (std::size_t a = 0; a < touched.size(); ++a) {
    const int ra = touched[a];
    const double wa = w.weight[static_cast<std::size_t>(ra)];
    for (std::size_t b = a; b < touched.size(); ++b) {
      const int rb = touched[b];
      system.ata[AtaIndex(std::min(ra, rb), std::max(ra, rb))] +=
          wa * w.weight[static_cast<std::size_t>(rb)];
    }
    for (int ch = 0; ch < kChannels; ++ch) {
      system.aty[static_cast<std::size_t>(ch)][static_cast<std::size_t>(ra)] +=
          wa * values[static_cast<std::size_t>(ch)];
    }
  }
  for (int ch = 0; ch < kChannels; ++ch) {
    system.yty[static_cast<std::size_t>(ch)] +=
        values[static_cast<std::size_t>(ch)] * values[static_cast<std::size_t>(ch)];
  }
  ++system.samples;
  system.weight += weight;
}

template <int kChannels>
void Symmetrise(RegionSystem<kChannels>& system) {
  for (int a = 0; a < kModelRegions; ++a) {
    for (int b = 0; b < a; ++b) {
      system.ata[AtaIndex(a, b)] = system.ata[AtaIndex(b, a)];
    }
  }
}

}  // namespace

cv::Rect CoverageBox(const cv::Rect& bounds) {
  const int reach = kMaxKernelRadius + 1;
  return {bounds.x - reach, bounds.y - reach, bounds.width + 2 * reach + 1,
          bounds.height + 2 * reach + 1};
}

LumaSystem AccumulateLuma(const RegionCoverage& coverage, const std::vector<LumaSample>& samples,
                          const Kernel& kernel, std::size_t stride, bool by_position) {
  LumaSystem system;
  SampleWeights w;
  stride = std::max<std::size_t>(1, stride);
  for (std::size_t i = 0; i < samples.size(); i += by_position ? 1 : stride) {
    const LumaSample& s = samples[i];
    if (by_position && PositionHash(s.x, s.y) % stride != 0) continue;
    coverage.blurred(kernel, s.x, s.y, w);
    AddSample<1>(system, w, {s.value});
    w.clear();
  }
  Symmetrise(system);
  return system;
}

void LumaRows::add(double value, const SampleWeights& weights) {
  values_.push_back(value);
  for (const int region : weights.touched) {
    terms_.push_back({region, weights.weight[static_cast<std::size_t>(region)]});
  }
  first_.push_back(terms_.size());
}

LumaRows GatherLumaRows(const RegionCoverage& coverage, const std::vector<LumaSample>& samples,
                        const Kernel& kernel, std::size_t stride) {
  LumaRows rows;
  SampleWeights w;
  stride = std::max<std::size_t>(1, stride);
  rows.reserve((samples.size() + stride - 1) / stride);
  for (std::size_t i = 0; i < samples.size(); i += stride) {
    coverage.blurred(kernel, samples[i].x, samples[i].y, w);
    rows.add(samples[i].value, w);
    w.clear();
  }
  return rows;
}

LumaSystem AccumulateLuma(const LumaRows& rows, std::span<const double> weights) {
  assert(weights.empty() || weights.size() == rows.size());
  LumaSystem system;
  SampleWeights w;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    // Weighting a row by g is scaling its coverage and its value by √g.
    const double scale = weights.empty() ? 1.0 : std::sqrt(weights[i]);
    for (const LumaRows::Term& t : rows.terms(i)) {
      w.weight[static_cast<std::size_t>(t.region)] = t.weight * scale;
      w.touched.push_back(t.region);
    }
    AddSample<1>(system, w, {rows.value(i) * scale}, weights.empty() ? 1.0 : weights[i]);
    w.clear();
  }
  Symmetrise(system);
  return system;
}

ChromaSystem AccumulateChroma(const RegionCoverage& coverage,
                              const std::vector<ChromaSample>& samples, const Kernel& kernel,
                              std::size_t stride) {
  ChromaSystem system;
  SampleWeights w;
  stride = std::max<std::size_t>(1, stride);
  for (std::size_t i = 0; i < samples.size(); i += stride) {
    const ChromaSample& s = samples[i];
    coverage.blurred(kernel, s.x, s.y, w);
    AddSample<2>(system, w, {s.cb, s.cr});
    w.clear();
  }
  Symmetrise(system);
  return system;
}

std::vector<double> PredictLuma(const RegionCoverage& coverage,
                                const std::vector<LumaSample>& samples, const Kernel& kernel,
                                const std::array<double, kModelRegions>& colours) {
  std::vector<double> predicted;
  predicted.reserve(samples.size());
  SampleWeights w;
  for (const LumaSample& s : samples) {
    coverage.blurred(kernel, s.x, s.y, w);
    double v = 0;
    for (const int r : w.touched) {
      v += w.weight[static_cast<std::size_t>(r)] * colours[static_cast<std::size_t>(r)];
    }
    predicted.push_back(v);
    w.clear();
  }
  return predicted;
}

}  // namespace pintag::reading
