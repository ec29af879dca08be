#pragma once
// Soft decision over the whole code: which of the 32,768 keys, in which of the four orientations,
// explains the samples best under the palette model, and by how much it beats every other. This is
// the dictionary decode ArUco and AprilTag make on thresholded bits, made on the model instead:
// both payload copies, the parity and the orientation cells decide together, each cell weighed by
// what its pixels say.

#include <optional>

#include "pintag/codec/tag_key.hpp"
#include "reading/palette_model.hpp"

namespace pintag::reading {

/// For each orientation (element r of the sampled frame taken as C0), the labelling that explains
/// the samples best with the orientation cells fixed to the format's and every other cell free
/// (iterated conditional modes from the free fit's colours): where the search starts, and the
/// free reading the winner is held against.
struct SettledLabelling {
  Labels labels{};
  PaletteColours colours{};
  double residual = 1e300;
};
using SettledLabellings = std::array<SettledLabelling, 4>;
SettledLabellings SettleOrientations(const PaletteModel& model);

struct CodewordDecision {
  std::optional<TagKey> winner;  ///< the codeword explaining the samples best (not yet accepted)
  int quarter_turns = 0;         ///< element `quarter_turns` of the sampled frame is C0
  double residual = 0;           ///< the winner's weighted residual
  double lead = 0;    ///< the best other codeword's residual over the winner's (noise units)
  double excess = 0;  ///< the winner's residual over the best settled labelling's (noise units)
  /// The free model's residual (every region its own colour) in the same units: what any
  /// labelling's residual is measured against (codeword_search.hpp's callers set it).
  double free_residual = 0;
  int runner_up_distance = 0;  ///< cells in which the runner-up differs from the winner
  /// How much better than the winner's the best colour fit among the scored codewords is (Cb's
  /// and Cr's part of the residual, noise units, at least 0): the colour's preference for another
  /// codeword, whatever the luminance says.
  double chroma_deficit = 0;
  PaletteColours colours{};  ///< the winner's six colours
  int scored = 0;            ///< codewords whose exact residual was computed
};

/// Codewords of the winner's orientation scored again after the neighbourhood search, ranked by
/// the cost of flipping cells from the winner (SearchCodewords).
inline constexpr std::size_t kAroundWinner = 32;

/// The labelling codeword `key` gives the regions with element `quarter_turns` of the sampled
/// frame as C0.
Labels CodewordLabels(int key, int quarter_turns);

/// Ranks every (key, orientation) by the summed flip costs of the cells where it differs from that
/// orientation's settled labelling, scores the best `exact` exactly (colours refitted), then every
/// codeword within kNeighbourCells (7) cells of each orientation's best scored one, again around a
/// new best until none changes; then the best kAroundWinner of the winner's orientation ranked from
/// the winner itself, and the neighbourhoods again around a new winner. Colours are fitted under
/// the palette's order (PaletteModel::fit).
CodewordDecision SearchCodewords(const PaletteModel& model, const SettledLabellings& settled,
                                 std::size_t exact = 128);

}  // namespace pintag::reading
