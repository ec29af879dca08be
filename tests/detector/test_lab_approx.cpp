// The integer stand-ins against the codec's exact CIELAB conversion.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "candidates/lab_approx.hpp"
#include "candidates/redness.hpp"
#include "pintag/codec/cielab.hpp"
#include "pintag/codec/palette.hpp"
#include "pintag/detector/options.hpp"

namespace pintag::stage {
namespace {

std::uint8_t Clamp8(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

// Photo-like pixels: the palette under exposure changes, colour casts, mixing with black / white
// (blur at edges) and noise; plus skin, wood, brick, sky, foliage, paper, and random colours.
std::vector<Rgb8> PhotoLikePixels() {
  std::vector<Rgb8> pixels;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 6);
  const double casts[][3] = {
      {1, 1, 1}, {1.15, 1.0, 0.75}, {0.9, 1.0, 1.1}, {0.85, 0.95, 1.2}, {1.05, 1.05, 0.9}};
  std::vector<Rgb8> bases;
  bases.reserve(std::size(kPalette));
  for (const PaletteEntry& p : kPalette) bases.push_back(p.srgb);
  const Rgb8 others[] = {{224, 172, 140}, {141, 85, 36},   {198, 134, 66},  {255, 219, 172},
                         {150, 60, 40},   {178, 34, 34},   {135, 206, 235}, {34, 139, 34},
                         {240, 240, 230}, {120, 120, 120}, {200, 30, 60},   {255, 105, 180},
                         {128, 0, 128},   {0, 0, 255},     {255, 165, 0},   {90, 20, 20}};
  bases.insert(bases.end(), std::begin(others), std::end(others));
  for (const Rgb8& base : bases) {
    for (const auto& cast : casts) {
      for (double exposure : {0.35, 0.55, 0.75, 1.0, 1.2}) {
        for (double mix : {0.0, 0.25, 0.5}) {
          for (int rep = 0; rep < 4; ++rep) {
            const double target[] = {static_cast<double>(base.r), static_cast<double>(base.g),
                                     static_cast<double>(base.b)};
            double c[3];
            for (int k = 0; k < 3; ++k) {
              const double lin =
                  SrgbToLinear(static_cast<std::uint8_t>(target[k])) * cast[k] * exposure;
              const double mixed = lin * (1 - mix) + (rep % 2 ? 0.01 : 0.9) * mix;
              c[k] = LinearToSrgb(std::min(1.0, mixed)) + (rep >= 2 ? noise(rng) : 0);
            }
            pixels.push_back({Clamp8(c[0]), Clamp8(c[1]), Clamp8(c[2])});
          }
        }
      }
    }
  }
  std::uniform_int_distribution<int> u(0, 255);
  for (int i = 0; i < 20000; ++i) {
    pixels.push_back({static_cast<std::uint8_t>(u(rng)), static_cast<std::uint8_t>(u(rng)),
                      static_cast<std::uint8_t>(u(rng))});
  }
  return pixels;
}

TEST(LabApprox, WithinOneUnitOfExactOverTheSrgbCube) {
  const LabApprox& lab = LabApprox::Get();
  double worst_a = 0, worst_b = 0, worst_l = 0;
  for (int r = 0; r < 256; r += 5) {
    for (int g = 0; g < 256; g += 5) {
      for (int b = 0; b < 256; b += 5) {
        const Lab exact = SrgbToLab({static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                     static_cast<std::uint8_t>(b)});
        worst_a = std::max(worst_a, std::abs(lab.aStar(r, g, b) / 16.0 - exact.a));
        worst_b = std::max(worst_b, std::abs(lab.bStar(r, g, b) / 16.0 - exact.b));
        worst_l = std::max(worst_l, std::abs(lab.lStar(r, g, b) / 16.0 - exact.l));
      }
    }
  }
  std::printf("worst |error|: a* %.3f  b* %.3f  L* %.3f\n", worst_a, worst_b, worst_l);
  EXPECT_LT(worst_a, 1.0);
  EXPECT_LT(worst_b, 1.0);
  EXPECT_LT(worst_l, 1.0);
}

TEST(LabApprox, PaletteClassifiedAsExact) {
  const RednessThresholds t;
  for (const PaletteEntry& p : kPalette) {
    const Lab exact = SrgbToLab(p.srgb);
    const bool red = p.colour == PaletteColour::kRedOne || p.colour == PaletteColour::kRedZero;
    EXPECT_EQ(IsRedLab(exact.a, exact.b, t), red) << p.name;
    EXPECT_EQ(IsRedPixel(p.srgb.r, p.srgb.g, p.srgb.b, t), red) << p.name;
    // Bits are read in b*: 1 high, 0 low, either side of ~30.
    const double b = LabApprox::Get().bStar(p.srgb.r, p.srgb.g, p.srgb.b) / 16.0;
    EXPECT_NEAR(b, exact.b, 1.0) << p.name;
  }
}

TEST(LabApprox, PhotoLikePixelsClassifiedAsExact) {
  const RednessThresholds t;
  int compared = 0, near_boundary = 0, red = 0;
  for (const Rgb8& c : PhotoLikePixels()) {
    const Lab exact = SrgbToLab(c);
    // A pixel within 1 unit of a threshold may go either way (both the stand-in and a camera's
    // noise are far coarser than that); everywhere else the answers must be identical.
    if (std::abs(exact.a - t.min_a) < 1.0 || std::abs(exact.b - t.min_b) < 1.0) {
      ++near_boundary;
      continue;
    }
    ++compared;
    red += IsRedLab(exact.a, exact.b, t);
    ASSERT_EQ(IsRedPixel(c.r, c.g, c.b, t), IsRedLab(exact.a, exact.b, t))
        << int(c.r) << "," << int(c.g) << "," << int(c.b) << " a*=" << exact.a << " b*=" << exact.b;
    // The bit threshold in b* (palette mid-point ~30) classifies the same way too.
    const double b = LabApprox::Get().bStar(c.r, c.g, c.b) / 16.0;
    if (std::abs(exact.b - 30) >= 1.0) {
      ASSERT_EQ(b > 30, exact.b > 30);
    }
  }
  std::printf("%d pixels compared (%d red), %d within 1 unit of a threshold skipped\n", compared,
              red, near_boundary);
  EXPECT_GT(compared, 25000);
}

TEST(Redness, PrefilterNeverRejectsARedColour) {
  // Every colour of the sRGB cube (step 3) that the exact rule calls red, with 1 unit of slack,
  // has R − G >= kRednessPrefilter, so the cheap first test loses nothing.
  const RednessThresholds loose{29, -31};
  int reds = 0;
  for (int r = 0; r < 256; r += 3) {
    for (int g = 0; g < 256; g += 3) {
      if (r - g >= kRednessPrefilter) continue;
      for (int b = 0; b < 256; b += 3) {
        const Lab exact = SrgbToLab({static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                     static_cast<std::uint8_t>(b)});
        reds += IsRedLab(exact.a, exact.b, loose);
      }
    }
  }
  EXPECT_EQ(reds, 0);
}

TEST(Redness, PrefilterNeverRejectsARedColourAtTheDefaultThreshold) {
  // The same proof at the default thresholds (a* >= 20), every code of R and G, with 1 unit of
  // slack: the prefilter R − G >= kRednessPrefilter loses no colour the exact rule calls red.
  const RednessThresholds defaults;
  const RednessThresholds loose{defaults.min_a - 1, defaults.min_b - 1};
  int reds = 0;
  for (int r = 0; r < 256; ++r) {
    for (int g = 0; g < 256; ++g) {
      if (r - g >= kRednessPrefilter) continue;
      for (int b = 0; b < 256; b += 3) {
        const Lab exact = SrgbToLab({static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                                     static_cast<std::uint8_t>(b)});
        reds += IsRedLab(exact.a, exact.b, loose);
      }
    }
  }
  EXPECT_EQ(reds, 0);
}

TEST(Redness, TableAgreesWithLabApproxOnEveryColour) {
  // The pass over the frame uses RedTable; it must call red exactly the colours IsRedPixel does,
  // over all 2^24 of them, at the main and faint-pass defaults and at others either side (so
  // that a threshold tuned through DetectorOptions gets the same guarantee).
  const DetectorOptions defaults;
  for (const RednessThresholds t : {RednessThresholds{defaults.red_min_a, defaults.red_min_b},
                                    RednessThresholds{defaults.faint_red_min_a, defaults.red_min_b},
                                    RednessThresholds{10, -30}, RednessThresholds{35, 0}}) {
    const RedTable& table = RedTable::For(t);
    long long reds = 0, wrong = 0, below_least_lead = 0;
    int least_lead = 1 << 20;
    for (int r = 0; r < 256; ++r) {
      for (int g = 0; g < 256; ++g) {
        for (int b = 0; b < 256; ++b) {
          const bool red = IsRedPixel(r, g, b, t);
          reds += red;
          wrong += red != table.isRed(r, g, b);
          if (!red) continue;
          // The frame scan skips pixels whose lead is below the table's least red lead.
          const int lead = 4 * (r - g) + (b - g);
          below_least_lead += lead < table.leastRedLead();
          least_lead = std::min(least_lead, lead);
        }
      }
    }
    EXPECT_EQ(wrong, 0) << "a* >= " << t.min_a << ", b* >= " << t.min_b;
    EXPECT_GT(reds, 100000) << "a* >= " << t.min_a;  // the rule is not empty
    EXPECT_EQ(below_least_lead, 0) << "a* >= " << t.min_a;
    EXPECT_EQ(table.leastRedLead(), least_lead) << "a* >= " << t.min_a;  // and it is the least
  }
}

}  // namespace
}  // namespace pintag::stage
