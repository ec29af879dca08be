#include "reading/codeword_search.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <limits>
#include <vector>

namespace pintag::reading {
namespace {

// The levels the format fixes in orientation r: the outer red quadrants, 0 on C0, 1 elsewhere.
void FixOrientationCells(int r, Labels* labels, std::array<bool, kModelRegions>* fixed) {
  for (int e = 0; e < kElements; ++e) {
    for (int q = 0; q < kRedQuadrants; ++q) {
      if (q == InnerQuadrant(e)) continue;
      const int j = SampledRegion(32 + 4 * e + q, r);
      (*labels)[static_cast<std::size_t>(j)] = e == 0 ? kRed0 : kRed1;
      (*fixed)[static_cast<std::size_t>(j)] = true;
    }
  }
}

}  // namespace

SettledLabellings SettleOrientations(const PaletteModel& model) {
  SettledLabellings settled;
  for (int r = 0; r < 4; ++r) {
    Labels labels{};
    std::array<bool, kModelRegions> fixed{};
    labels[kQuietRegion] = kQuietLevel;
    labels[kBlackRegion] = kBlackLevel;
    fixed[kQuietRegion] = fixed[kBlackRegion] = true;
    FixOrientationCells(r, &labels, &fixed);
    // Every other cell starts on the side of the orientation cells' midpoint in Cb its free colour
    // lies on: the palette gives both classes the same two levels of yellowness (its ones low in
    // Cb), so the red orientation cells' zeros and ones set the split for the greens too. (A split
    // at each class's own mean would make half the greens ones on a tag whose greens are all
    // zeros, key 0's.)
    double zero_cb = 0, one_cb = 0;
    int zeros = 0, ones = 0;
    for (int j = 2; j < kModelRegions; ++j) {
      if (!fixed[static_cast<std::size_t>(j)]) continue;
      const double cb = model.freeColour(j)[1];
      if (labels[static_cast<std::size_t>(j)] == kRed0) {
        zero_cb += cb, ++zeros;
      } else {
        one_cb += cb, ++ones;
      }
    }
    const double mid = (zero_cb / std::max(zeros, 1) + one_cb / std::max(ones, 1)) / 2;
    for (int j = 2; j < kModelRegions; ++j) {
      if (fixed[static_cast<std::size_t>(j)]) continue;
      const bool green = (j - 2) % kCellsPerElement >= kRedQuadrants;
      const bool one = model.freeColour(j)[1] < mid;
      labels[static_cast<std::size_t>(j)] =
          green ? (one ? kGreen1 : kGreen0) : (one ? kRed1 : kRed0);
    }
    SettledLabelling& s = settled[static_cast<std::size_t>(r)];
    model.settle(&labels, fixed, &s.colours);
    s.labels = labels;
    s.colours = model.fit(labels, &s.residual);
  }
  return settled;
}

Labels CodewordLabels(int key, int quarter_turns) {
  Labels labels{};
  labels[kQuietRegion] = kQuietLevel;
  labels[kBlackRegion] = kBlackLevel;
  const std::uint64_t code = Codebook()[static_cast<std::size_t>(key)];
  for (int cell = 0; cell < kCanonicalCells; ++cell) {
    const bool one = ((code >> cell) & 1U) != 0;
    labels[static_cast<std::size_t>(SampledRegion(cell, quarter_turns))] =
        cell < 32 ? (one ? kGreen1 : kGreen0) : (one ? kRed1 : kRed0);
  }
  return labels;
}

CodewordDecision SearchCodewords(const PaletteModel& model, const SettledLabellings& settled,
                                 std::size_t exact) {
  CodewordDecision decision;
  double free_best = std::numeric_limits<double>::infinity();
  for (const SettledLabelling& s : settled) free_best = std::min(free_best, s.residual);

  struct Candidate {
    double cost;
    int key;
    int turns;
  };
  const std::vector<std::uint64_t>& book = Codebook();
  // Keeps in `ranked` (ascending, at most `count`) the codewords of orientation r whose cells
  // cost least to flip from `labels` with `colours` held, among those `skip` lets through.
  const auto rank = [&](const Labels& labels, const PaletteColours& colours, int r,
                        std::size_t count, const auto& skip, std::vector<Candidate>* ranked) {
    if (count == 0) return;
    std::array<double, kCanonicalCells> cost{};
    std::uint64_t read = 0;
    for (int c = 0; c < kCanonicalCells; ++c) {
      const int j = SampledRegion(c, r);
      cost[static_cast<std::size_t>(c)] = model.flipCost(labels, colours, j);
      if (IsOneLevel(labels[static_cast<std::size_t>(j)])) read |= std::uint64_t{1} << c;
    }
    // The summed cost of any set of differing cells, a byte of the mask at a time.
    std::array<std::array<double, 256>, kCanonicalCells / 8> by_byte{};
    for (std::size_t byte = 0; byte < by_byte.size(); ++byte) {
      for (unsigned v = 1; v < 256; ++v) {
        by_byte[byte][v] = by_byte[byte][v & (v - 1)] +
                           cost[byte * 8 + static_cast<std::size_t>(std::countr_zero(v))];
      }
    }
    for (int k = 0; k < kKeyCount; ++k) {
      const std::uint64_t differ = book[static_cast<std::size_t>(k)] ^ read;
      double total = 0;
      for (std::size_t byte = 0; byte < by_byte.size(); ++byte) {
        total += by_byte[byte][(differ >> (8 * byte)) & 0xFFU];
      }
      if ((ranked->size() < count || total < ranked->back().cost) && !skip(k)) {
        if (ranked->size() == count) ranked->pop_back();
        const Candidate candidate{total, k, r};
        ranked->insert(std::upper_bound(
                           ranked->begin(), ranked->end(), candidate,
                           [](const Candidate& x, const Candidate& y) { return x.cost < y.cost; }),
                       candidate);
      }
    }
  };
  std::vector<Candidate> ranked;
  ranked.reserve(exact + 1);
  for (int r = 0; r < 4; ++r) {
    const SettledLabelling& h = settled[static_cast<std::size_t>(r)];
    rank(
        h.labels, h.colours, r, exact, [](int) { return false; }, &ranked);
  }

  struct Scored {
    double residual;
    Candidate candidate;
    PaletteColours colours;
    double chroma_residual;  // Cb's and Cr's part of `residual`
  };
  std::vector<Scored> scored;
  std::vector<bool> is_scored(4 * static_cast<std::size_t>(kKeyCount));
  const auto slot = [](int turns, int key) {
    return static_cast<std::size_t>(turns) * kKeyCount + static_cast<std::size_t>(key);
  };
  // Each codeword is fitted from the level system of a labelling near it, moving only the cells
  // where the two differ: the labelling its orientation was ranked from (the ranking puts first
  // the codewords that differ from it least, though that can still be many cells), the codeword a
  // neighbourhood is centred on (at most 7 cells), or the winner (the search's instructions on
  // the load scenes 0.96 -> 0.59 G; callgrind).
  struct Base {
    Labels labels{};
    LevelSystem system;
  };
  const auto base_of = [&](const Labels& labels) {
    return Base{labels, model.levelSystem(labels)};
  };
  const auto score = [&](const Candidate& c, const Base& base) {
    is_scored[slot(c.turns, c.key)] = true;
    const Labels labels = CodewordLabels(c.key, c.turns);
    double residual = 0;
    ChannelResiduals parts{};
    const PaletteColours colours =
        model.fit(model.relabelled(base.system, base.labels, labels), &residual, &parts);
    scored.push_back({residual, c, colours, parts[1] + parts[2]});
  };
  std::array<Base, 4> settled_bases;
  for (std::size_t r = 0; r < 4; ++r) settled_bases[r] = base_of(settled[r].labels);
  for (const Candidate& c : ranked) score(c, settled_bases[static_cast<std::size_t>(c.turns)]);
  const auto by_residual = [](const Scored& a, const Scored& b) { return a.residual < b.residual; };
  std::sort(scored.begin(), scored.end(), by_residual);
  // A lead over the runner-up among those scored says nothing about codewords the ranking left
  // out: every codeword within 7 cells of the best scored one of each orientation is scored too,
  // again around a new best until none changes. Around the winner's orientation alone was not
  // enough: the ranking's cell costs add up from each orientation's free labelling, and where
  // that labelling is many cells off, the true codeword in another orientation ranked 562nd of
  // its orientation while explaining the pixels better than the winner (a held-out 18 px tag,
  // read as another key; docs/DETECTOR.md).
  std::vector<int> neighbours;
  neighbours.reserve(NeighbourKeyOffsets().size());
  std::array<int, 4> centre_key{-1, -1, -1, -1};  // the codeword each orientation last centred on
  const auto score_neighbourhoods = [&] {
    for (int round = 0; round < 4 && !scored.empty(); ++round) {
      const std::size_t before = scored.size();
      bool moved = false;
      for (int r = 0; r < 4; ++r) {
        const auto best_r = std::find_if(scored.begin(), scored.end(),
                                         [&](const Scored& s) { return s.candidate.turns == r; });
        if (best_r == scored.end() ||
            best_r->candidate.key == centre_key[static_cast<std::size_t>(r)]) {
          continue;
        }
        moved = true;
        const int centre = best_r->candidate.key;
        centre_key[static_cast<std::size_t>(r)] = centre;
        neighbours.clear();
        for (const int d : NeighbourKeyOffsets()) neighbours.push_back(centre ^ d);
        std::sort(neighbours.begin(), neighbours.end());  // scored in key order, as always
        const Base around_centre = base_of(CodewordLabels(centre, r));
        for (const int k : neighbours) {
          if (!is_scored[slot(r, k)]) score({0, k, r}, around_centre);
        }
      }
      if (!moved || scored.size() == before) break;
      std::sort(scored.begin(), scored.end(), by_residual);
    }
  };
  score_neighbourhoods();
  // Seven cells is a radius, not a guarantee: a codeword eight cells from the winner can explain
  // the samples better, and the ranking from the free labelling may have put it far down (tuning
  // seed 22, frame 2285: the truth, 8 cells from the winner in the same orientation, better by
  // 122 noise units, never scored). So the winner's orientation is ranked again by the cost of
  // flipping cells from the winner itself, its colours held, and the best of those not yet scored
  // are scored; around a new winner the neighbourhoods are searched again.
  std::vector<Candidate> around;
  for (int pass = 0; pass < 2 && !scored.empty(); ++pass) {
    const Candidate winner = scored.front().candidate;
    const Base winner_base = base_of(CodewordLabels(winner.key, winner.turns));
    around.clear();
    rank(
        winner_base.labels, scored.front().colours, winner.turns, kAroundWinner,
        [&](int k) { return is_scored[slot(winner.turns, k)]; }, &around);
    for (const Candidate& c : around) score(c, winner_base);
    std::sort(scored.begin(), scored.end(), by_residual);
    if (scored.front().candidate.key == winner.key &&
        scored.front().candidate.turns == winner.turns) {
      break;
    }
    score_neighbourhoods();
  }
  decision.scored = static_cast<int>(scored.size());
  if (scored.size() < 2) return decision;
  const Scored& best = scored[0];
  decision.winner = TagKey(static_cast<std::uint16_t>(best.candidate.key));
  decision.quarter_turns = best.candidate.turns;
  decision.residual = best.residual;
  decision.lead = scored[1].residual - best.residual;
  decision.excess = best.residual - free_best;
  decision.colours = best.colours;
  const std::uint64_t a = book[static_cast<std::size_t>(best.candidate.key)];
  const std::uint64_t b = book[static_cast<std::size_t>(scored[1].candidate.key)];
  decision.runner_up_distance =
      scored[1].candidate.turns == best.candidate.turns ? std::popcount(a ^ b) : kCanonicalCells;
  double least_chroma = best.chroma_residual;
  for (const Scored& s : scored) least_chroma = std::min(least_chroma, s.chroma_residual);
  decision.chroma_deficit = best.chroma_residual - least_chroma;
  return decision;
}

}  // namespace pintag::reading
