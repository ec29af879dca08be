// Stage 3b: clustering blobs into tag candidates and placing them at elements.

#include <gtest/gtest.h>

#include "candidates/grouping.hpp"
#include "homography.hpp"

namespace pintag::stage {
namespace {

RedBlob Blob(double x, double y, double d) {
  RedBlob b;
  b.centroid = {x, y};
  b.major = b.minor = d;
  b.area = static_cast<int>(3.14 * d * d / 4);
  b.fill = 1;
  return b;
}

// Elements of a tag with square side s at (x, y): centres 0.25 s / 0.75 s, disk diameter 0.2 s.
void AddTag(std::vector<RedBlob>* blobs, double x, double y, double s, int skip = -1) {
  const double c[4][2] = {{0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75}};
  for (int e = 0; e < 4; ++e) {
    if (e != skip) blobs->push_back(Blob(x + c[e][0] * s, y + c[e][1] * s, 0.2 * s));
  }
}

TEST(Grouping, GroupsOfMoreThanMaxBlobsAreLeftOut) {
  std::vector<RedBlob> blobs;
  AddTag(&blobs, 100, 100, 100);
  for (int i = 0; i < 12; ++i) blobs.push_back(Blob(400 + 15 * i, 300, 6));  // a chain of 12
  EXPECT_EQ(ClusterBlobs(blobs, {800, 500}).size(), 2u);
  const auto clusters = ClusterBlobs(blobs, {800, 500}, 3, 9);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].blobs.size(), 4u);
}

TEST(Grouping, TwoTagsTwoClustersAndStrayBlobsNone) {
  std::vector<RedBlob> blobs;
  AddTag(&blobs, 100, 100, 100);
  AddTag(&blobs, 400, 120, 60, 2);      // one element hidden
  blobs.push_back(Blob(700, 400, 20));  // alone
  const auto clusters = ClusterBlobs(blobs, {800, 500});
  ASSERT_EQ(clusters.size(), 2u);
  for (const BlobCluster& c : clusters) {
    if (c.blobs.size() == 4) {
      EXPECT_TRUE(c.roi.contains({100, 100}) && c.roi.contains({199, 199}));
    } else {
      EXPECT_EQ(c.blobs.size(), 3u);
      // The region reaches the hidden element's corner of the square too.
      EXPECT_TRUE(c.roi.contains({459, 179}));
    }
  }
}

// The faint pass also tries pairs: two neighbouring elements (the far side of the square and its
// quiet zone are then 1.8 element spacings away) or two diagonal ones.
TEST(Grouping, PairsFormClustersOnlyWhenAskedAndTheirRegionHoldsTheSquare) {
  for (const int hidden_a : {2, 1}) {
    std::vector<RedBlob> blobs;
    AddTag(&blobs, 100, 100, 100);
    // Keep elements 0 and 1 (neighbours), or 0 and 2 (diagonal).
    const int hidden_b = 3;
    blobs.erase(blobs.begin() + hidden_b);
    blobs.erase(blobs.begin() + hidden_a);
    ASSERT_EQ(blobs.size(), 2u);
    EXPECT_TRUE(ClusterBlobs(blobs, {800, 500}).empty());
    const auto clusters = ClusterBlobs(blobs, {800, 500}, 2);
    ASSERT_EQ(clusters.size(), 1u);
    EXPECT_EQ(clusters[0].min_elements, 2);
    // The square (100 … 200) and nearly all of its quiet zone (0.15 of the side).
    EXPECT_TRUE(clusters[0].roi.contains({86, 86}) && clusters[0].roi.contains({214, 214}))
        << "hidden " << hidden_a << ", roi " << clusters[0].roi;
  }
}

TEST(Grouping, AssignsBlobsToElementSlots) {
  std::vector<RedBlob> blobs;
  AddTag(&blobs, 100, 100, 100, 1);
  const Quad quad = {cv::Point2d(100, 100), {200, 100}, {200, 200}, {100, 200}};
  const ElementAssignment a = AssignElements(HomographyFromQuad(quad), blobs, {0, 1, 2});
  EXPECT_EQ(a.found, 3);
  EXPECT_FALSE(a.conflict);
  EXPECT_EQ(a.blob[0], 0);
  EXPECT_EQ(a.blob[1], -1);
  EXPECT_EQ(a.blob[2], 1);
  EXPECT_EQ(a.blob[3], 2);
  blobs.push_back(Blob(150, 150, 10));  // red in the middle of the square: not a tag
  EXPECT_TRUE(AssignElements(HomographyFromQuad(quad), blobs, {0, 1, 2, 3}).conflict);
}

TEST(Grouping, SmallRedSpecksAlongTheSquaresEdgeAreFringesNotConflicts) {
  // Side 60 px: element blobs of diameter 12 px (area 113). Demosaicing leaves specks of false red
  // on the square's black-to-white edge.
  std::vector<RedBlob> blobs;
  AddTag(&blobs, 100, 100, 60);
  const Quad quad = {cv::Point2d(100, 100), {160, 100}, {160, 160}, {100, 160}};
  const cv::Matx33d h = HomographyFromQuad(quad);
  const auto with = [&](RedBlob extra) {
    std::vector<RedBlob> all = blobs;
    all.push_back(extra);
    return AssignElements(h, all, {0, 1, 2, 3, 4});
  };
  const RedBlob speck_on_edge = Blob(100 + 0.47 * 60, 100 + 0.96 * 60, 3);  // area 7
  const ElementAssignment fringe = with(speck_on_edge);
  EXPECT_FALSE(fringe.conflict);
  EXPECT_EQ(fringe.found, 4);
  EXPECT_FALSE(with(Blob(100 + 0.5 * 60, 100 + 0.92 * 60, 4.3)).conflict);  // area 14
  // The same speck in the middle of the square, or 0.15 from its edge: red the format lacks.
  EXPECT_TRUE(with(Blob(130, 130, 3)).conflict);
  EXPECT_TRUE(with(Blob(100 + 0.5 * 60, 100 + 0.85 * 60, 3)).conflict);
  // On the edge but of more than 16 px (a sixth of an element blob here): not a speck.
  EXPECT_TRUE(with(Blob(100 + 0.5 * 60, 100 + 0.92 * 60, 5)).conflict);  // area 19
  // Near the edge but inside an element's green ring (0.2 from its centre): not a fringe.
  EXPECT_TRUE(with(Blob(100 + 0.25 * 60, 100 + 0.07 * 60, 3)).conflict);
  // A speck at an element slot that already has its blob, outside its red disk (radius 0.10) but
  // inside the slot's tolerance (0.075 along each axis), is two blobs in one slot.
  EXPECT_TRUE(with(Blob(100 + 0.325 * 60, 100 + 0.325 * 60, 3)).conflict);
  // Around a 24 px square (element blobs of area 18) a 7 px speck is more than a quarter.
  std::vector<RedBlob> small;
  AddTag(&small, 300, 100, 24);
  small.push_back(Blob(300 + 0.47 * 24, 100 + 0.96 * 24, 3));
  const Quad small_quad = {cv::Point2d(300, 100), {324, 100}, {324, 124}, {300, 124}};
  EXPECT_TRUE(AssignElements(HomographyFromQuad(small_quad), small, {0, 1, 2, 3, 4}).conflict);
}

// A red disk whose darker bit-0 quadrants fell below the redness threshold passes as its bit-1
// quadrants alone: two or three blobs at one slot, each inside the disk. They are one element.
TEST(Grouping, PiecesOfOneRedDiskAreOneElementNotAConflict) {
  const double s = 100;
  std::vector<RedBlob> blobs;
  AddTag(&blobs, 100, 100, s, 0);  // elements 1-3 whole; element 0 in pieces, below
  // Quadrants q = 0 (up to right) and 2 (down to left) of element 0, whose centre is (125, 125):
  // a quarter disk's centroid lies 0.042 S from the centre along each axis.
  const int first_piece = static_cast<int>(blobs.size());
  blobs.push_back(Blob(125 + 4.2, 125 - 4.2, 0.1 * s));
  blobs.push_back(Blob(125 - 4.2, 125 + 4.2, 0.12 * s));  // the larger piece
  const Quad quad = {cv::Point2d(100, 100), {200, 100}, {200, 200}, {100, 200}};
  const cv::Matx33d h = HomographyFromQuad(quad);
  const ElementAssignment a = AssignElements(h, blobs, {0, 1, 2, 3, 4});
  EXPECT_FALSE(a.conflict);
  EXPECT_EQ(a.found, 4);
  EXPECT_EQ(a.blob[0], first_piece + 1);
  // A piece whose centroid lies outside the disk (0.075 S along each axis: 0.106 S from the
  // centre, in the green ring) is not part of it.
  blobs.push_back(Blob(125 + 7.5, 125 + 7.5, 0.05 * s));
  EXPECT_TRUE(AssignElements(h, blobs, {0, 1, 2, 3, 4, 5}).conflict);
}

}  // namespace
}  // namespace pintag::stage
