#include "lead_tail.hpp"

#include <cmath>

namespace pintag::bench {

double LeadTail::rateAbove(double lead) const {
  if (above == 0 || readings == 0) return 0;
  const double share = static_cast<double>(above) / static_cast<double>(readings);
  return scale > 0 ? share * std::exp(-(lead - from) / scale) : 0;
}

double LeadTail::leadFor(double rate) const {
  if (above == 0 || readings == 0 || rate <= 0) return from;
  const double share = static_cast<double>(above) / static_cast<double>(readings);
  return from + scale * std::log(share / rate);
}

LeadTail FitLeadTail(std::span<const double> wrong_leads, std::size_t readings, double from) {
  LeadTail tail;
  tail.readings = readings;
  tail.from = from;
  double sum = 0;
  for (const double lead : wrong_leads) {
    if (lead > from) {
      ++tail.above;
      sum += lead - from;
    }
  }
  if (tail.above > 0) tail.scale = sum / static_cast<double>(tail.above);
  return tail;
}

}  // namespace pintag::bench
