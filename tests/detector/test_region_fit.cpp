// The free model's solve (reading/region_fit.cpp) against OpenCV's: SolveFree factorises with its
// own Cholesky, claimed to be cv::solve(…, DECOMP_CHOLESKY)'s operations in the same order, so the
// colours and residuals must come out bit for bit as a per-channel cv::solve gives them. Every
// lead and threshold of the model reader was measured on the cv::solve results.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <random>

#include "reading/region_fit.hpp"

namespace pintag::reading {
namespace {

// Normal equations of `count` samples, each a blur-like mix of a few regions, values random.
template <int kChannels>
RegionSystem<kChannels> RandomSystem(std::mt19937& rng, int count, int regions_seen) {
  RegionSystem<kChannels> system;
  std::uniform_int_distribution<int> region(0, regions_seen - 1);
  std::uniform_real_distribution<double> share(0.05, 1.0), value(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    std::array<double, kModelRegions> mix{};
    for (int n = 0; n < 4; ++n) mix[static_cast<std::size_t>(region(rng))] += share(rng);
    double total = 0;
    for (const double m : mix) total += m;
    std::array<double, kChannels> y{};
    for (double& v : y) v = value(rng);
    for (int j = 0; j < kModelRegions; ++j) {
      const double wj = mix[static_cast<std::size_t>(j)] / total;
      for (int k = 0; k < kModelRegions; ++k) {
        system.ata[AtaIndex(j, k)] += wj * mix[static_cast<std::size_t>(k)] / total;
      }
      for (int ch = 0; ch < kChannels; ++ch) {
        system.aty[static_cast<std::size_t>(ch)][static_cast<std::size_t>(j)] +=
            wj * y[static_cast<std::size_t>(ch)];
      }
    }
    for (int ch = 0; ch < kChannels; ++ch) {
      system.yty[static_cast<std::size_t>(ch)] +=
          y[static_cast<std::size_t>(ch)] * y[static_cast<std::size_t>(ch)];
    }
    ++system.samples;
    system.weight += 1;
  }
  return system;
}

// The solve as it was written with OpenCV: ridge, then cv::solve and the residual per channel.
template <int kChannels>
FreeFit<kChannels> SolveWithOpenCv(const RegionSystem<kChannels>& system) {
  FreeFit<kChannels> fit;
  using Square = cv::Matx<double, kModelRegions, kModelRegions>;
  Square m;
  double trace = 0;
  for (int a = 0; a < kModelRegions; ++a) {
    for (int b = 0; b < kModelRegions; ++b) m(a, b) = system.at(a, b);
    trace += m(a, a);
  }
  const double ridge = 0.01 * trace / kModelRegions;
  Square ridged = m;
  for (int a = 0; a < kModelRegions; ++a) ridged(a, a) += ridge;
  for (int ch = 0; ch < kChannels; ++ch) {
    const auto& aty = system.aty[static_cast<std::size_t>(ch)];
    cv::Matx<double, kModelRegions, 1> rhs, x;
    double mean = 0;
    for (int a = 0; a < kModelRegions; ++a) mean += aty[static_cast<std::size_t>(a)];
    mean /= system.weight;
    for (int a = 0; a < kModelRegions; ++a)
      rhs(a) = aty[static_cast<std::size_t>(a)] + ridge * mean;
    if (!cv::solve(ridged, rhs, x, cv::DECOMP_CHOLESKY)) return fit;
    const cv::Matx<double, kModelRegions, 1> mx = m * x;
    double residual = system.yty[static_cast<std::size_t>(ch)];
    for (int a = 0; a < kModelRegions; ++a) {
      residual += x(a) * (mx(a) - 2 * aty[static_cast<std::size_t>(a)]);
      fit.colour[static_cast<std::size_t>(ch)][static_cast<std::size_t>(a)] = x(a);
    }
    fit.residual[static_cast<std::size_t>(ch)] = std::max(0.0, residual);
  }
  fit.ok = true;
  return fit;
}

template <int kChannels>
void ExpectSameBits(const FreeFit<kChannels>& ours, const FreeFit<kChannels>& theirs, int trial) {
  ASSERT_EQ(ours.ok, theirs.ok) << "trial " << trial;
  for (int ch = 0; ch < kChannels; ++ch) {
    EXPECT_EQ(ours.residual[static_cast<std::size_t>(ch)],
              theirs.residual[static_cast<std::size_t>(ch)])
        << "trial " << trial << " channel " << ch;
    for (int a = 0; a < kModelRegions; ++a) {
      EXPECT_EQ(ours.colour[static_cast<std::size_t>(ch)][static_cast<std::size_t>(a)],
                theirs.colour[static_cast<std::size_t>(ch)][static_cast<std::size_t>(a)])
          << "trial " << trial << " channel " << ch << " region " << a;
    }
  }
}

TEST(RegionFit, SolvesBitForBitAsOpenCvsCholeskyDoes) {
  std::mt19937 rng(1129);
  for (int trial = 0; trial < 40; ++trial) {
    // Few samples (regions barely seen, the ridge doing the work) to many.
    const int count = 20 + 40 * trial;
    const RegionSystem<1> luma = RandomSystem<1>(rng, count, kModelRegions);
    const RegionSystem<2> chroma = RandomSystem<2>(rng, count, kModelRegions);
    ExpectSameBits(SolveFree(luma), SolveWithOpenCv(luma), trial);
    ExpectSameBits(SolveFree(chroma), SolveWithOpenCv(chroma), trial);
    ASSERT_TRUE(SolveFree(luma).ok);
  }
}

TEST(RegionFit, RefusesAnEmptySystemAndAgreesWithOpenCvWhereRegionsAreUnseen) {
  EXPECT_FALSE(SolveFree(RegionSystem<1>{}).ok);
  EXPECT_FALSE(SolveFree(RegionSystem<2>{}).ok);
  // Half the regions never seen: only the ridge keeps the system solvable.
  std::mt19937 rng(5);
  const RegionSystem<2> half = RandomSystem<2>(rng, 300, kModelRegions / 2);
  ExpectSameBits(SolveFree(half), SolveWithOpenCv(half), -1);
}

}  // namespace
}  // namespace pintag::reading
