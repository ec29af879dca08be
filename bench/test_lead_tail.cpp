// The misread-rate estimate of the reader probe (src/lead_tail.hpp) on leads drawn from a known
// tail: it must recover the tail's scale and the share of readings past a threshold.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "lead_tail.hpp"

namespace pintag::bench {
namespace {

// Uniform in (0, 1) from the engine's raw output, which the standard fixes for mt19937 (the
// distributions' algorithms it leaves to each library).
double Uniform(std::mt19937& rng) {
  return (static_cast<double>(rng()) + 0.5) / 4294967296.0;
}

struct Drawn {
  std::vector<double> wrong_leads;
  std::size_t readings = 0;
};

// 200,000 readings, 1 % with a wrong winner: 60 % of those lead by 0-4, the rest by 4 plus an
// exponential of scale 3.
Drawn DrawLeads() {
  std::mt19937 rng(20261129);
  Drawn d;
  d.readings = 200000;
  for (std::size_t i = 0; i < d.readings / 100; ++i) {
    d.wrong_leads.push_back(Uniform(rng) < 0.6 ? 4 * Uniform(rng) : 4 - 3 * std::log(Uniform(rng)));
  }
  return d;
}

TEST(LeadTail, RecoversTheScaleAndTheShareAboveAThreshold) {
  const Drawn d = DrawLeads();
  const LeadTail tail = FitLeadTail(d.wrong_leads, d.readings, 4);
  EXPECT_NEAR(tail.scale, 3.0, 0.15);
  EXPECT_NEAR(static_cast<double>(tail.above), 800, 3 * std::sqrt(800.0));
  // The true share past 10: 0.01 × 0.4 × e^(−2) = 5.4e-4; past 16, 7.3e-5.
  EXPECT_NEAR(tail.rateAbove(10), 5.41e-4, 0.6e-4);
  EXPECT_NEAR(tail.rateAbove(16), 7.33e-5, 1.2e-5);
  // What was counted agrees with what is estimated where there are counts to compare.
  std::size_t past10 = 0;
  for (const double lead : d.wrong_leads) past10 += lead > 10 ? 1 : 0;
  EXPECT_NEAR(tail.rateAbove(10) * static_cast<double>(d.readings), static_cast<double>(past10),
              3 * std::sqrt(static_cast<double>(past10)));
}

TEST(LeadTail, LeadForInvertsRateAbove) {
  const Drawn d = DrawLeads();
  const LeadTail tail = FitLeadTail(d.wrong_leads, d.readings, 4);
  for (const double rate : {1e-4, 1e-6, 1e-8}) {
    EXPECT_NEAR(tail.rateAbove(tail.leadFor(rate)) / rate, 1.0, 1e-9);
  }
  EXPECT_GT(tail.leadFor(1e-7), tail.leadFor(1e-6));
}

TEST(LeadTail, NothingAboveTheFitGivesNoRate) {
  const std::vector<double> leads = {0.5, 1.0, 3.9};
  const LeadTail tail = FitLeadTail(leads, 1000, 4);
  EXPECT_EQ(tail.above, 0U);
  EXPECT_EQ(tail.rateAbove(30), 0.0);
  EXPECT_EQ(tail.leadFor(1e-6), 4.0);
}

}  // namespace
}  // namespace pintag::bench
