// Stage 3b for one cluster, on the case the blobs must rescue: a small tag with a dim, thin quiet
// zone on dark ground, blurred, where the thresholded outline never separates the square.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "candidates/cluster_quads.hpp"
#include "homography.hpp"

namespace pintag::stage {
namespace {

constexpr int kSupersample = 8;

struct DimTag {
  cv::Mat dark;                // min(R, G, B) of the frame
  Quad corners;                // the square, clockwise, px
  std::vector<RedBlob> blobs;  // at the element centres
};

// A 28 px square turned by `roll_deg`, its quiet zone 0.15 of the side wide at code 130, the
// square itself 35 (its coloured elements are not black in min(R, G, B) once blurred), on ground
// at 12, blurred with σ 1.5 px.
DimTag MakeDimTag(double roll_deg) {
  const cv::Size size(120, 120);
  const cv::Point2d centre(60.3, 58.8);
  const double side = 28;
  const double a = roll_deg * CV_PI / 180;
  const cv::Point2d u(std::cos(a), std::sin(a)), v(-std::sin(a), std::cos(a));
  const auto at = [&](double x, double y) {
    return centre + (x - 0.5) * side * u + (y - 0.5) * side * v;
  };
  const auto polygon = [&](double lo, double hi) {
    std::vector<cv::Point> points;
    for (const auto& [x, y] :
         std::array<std::pair<double, double>, 4>{{{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}}}) {
      const cv::Point2d p = at(x, y);
      // Pixel (x, y) covers ±0.5 around its centre: supersampled pixel k covers [k, k + 1) / n −
      // 0.5.
      points.emplace_back(cvRound((p.x + 0.5) * kSupersample), cvRound((p.y + 0.5) * kSupersample));
    }
    return points;
  };
  cv::Mat big(size.height * kSupersample, size.width * kSupersample, CV_32F, cv::Scalar(12));
  cv::fillConvexPoly(big, polygon(-0.15, 1.15), cv::Scalar(130));
  cv::fillConvexPoly(big, polygon(0, 1), cv::Scalar(35));
  cv::Mat small;
  cv::resize(big, small, size, 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(small, small, {0, 0}, 1.5);
  DimTag tag;
  small.convertTo(tag.dark, CV_8U);
  tag.corners = {at(0, 0), at(1, 0), at(1, 1), at(0, 1)};
  const std::array<cv::Point2d, 4> elements = {at(0.25, 0.25), at(0.75, 0.25), at(0.75, 0.75),
                                               at(0.25, 0.75)};
  // Three of the four elements show red, their centroids a little off as a blurred core's are.
  const std::array<cv::Point2d, 3> error = {{{0.3, -0.2}, {-0.25, 0.3}, {0.2, 0.25}}};
  for (int e = 1; e < 4; ++e) {
    RedBlob b;
    b.centroid = elements[e] + error[e - 1];
    b.area = 6;
    b.major = 3;
    b.minor = 2.6;
    b.fill = 0.9;
    tag.blobs.push_back(b);
  }
  return tag;
}

// Largest distance from a corner of `quad` to the nearest truth corner.
double WorstCornerError(const Quad& quad, const Quad& truth) {
  double worst = 0;
  for (const cv::Point2d& t : truth) {
    double best = 1e9;
    for (const cv::Point2d& q : quad) best = std::min(best, cv::norm(q - t));
    worst = std::max(worst, best);
  }
  return worst;
}

std::vector<cv::Point2d> Centres(const std::vector<RedBlob>& blobs) {
  std::vector<cv::Point2d> centres;
  centres.reserve(blobs.size());
  for (const RedBlob& b : blobs) centres.push_back(b.centroid);
  return centres;
}

// How many of `quads` step 4's edge refinement brings within 0.4 px of the square.
int RefinedNearTheSquare(std::vector<Quad> quads, const DimTag& tag) {
  int near = 0;
  for (Quad& q : quads) {
    EXPECT_GT(SignedArea2(q), 0);  // clockwise on screen
    if (RefineCorners(tag.dark, {0, 0}, &q)) near += WorstCornerError(q, tag.corners) < 0.4;
  }
  return near;
}

TEST(ClusterQuads, BlobsPlaceTheSquareWhenItsOutlineIsLost) {
  for (const double roll : {0.0, 23.0, 61.0}) {
    const DimTag tag = MakeDimTag(roll);
    BlobCluster cluster;
    cluster.blobs = {0, 1, 2};
    cluster.roi = cv::Rect(0, 0, tag.dark.cols, tag.dark.rows);
    // The outline's quads do not give the square …
    EXPECT_EQ(RefinedNearTheSquare(ClusterQuads(tag.dark, cluster, tag.blobs, 20), tag), 0)
        << "roll " << roll;
    // … the three blobs' quads do, once step 4 has refined them.
    const std::vector<Quad> placed = QuadsFromElements(Centres(tag.blobs));
    EXPECT_EQ(placed.size(), 3U);
    EXPECT_GE(RefinedNearTheSquare(placed, tag), 1) << "roll " << roll;
  }
}

TEST(ClusterQuads, FourBlobsInAnyOrderGiveOnePerspectiveQuad) {
  const DimTag tag = MakeDimTag(35);
  std::vector<cv::Point2d> centres = Centres(tag.blobs);
  const double a = 35 * CV_PI / 180;
  const cv::Point2d u(std::cos(a), std::sin(a)), v(-std::sin(a), std::cos(a));
  centres.push_back(cv::Point2d(60.3, 58.8) - 7.0 * u - 7.0 * v);  // element 0
  std::swap(centres[0], centres[3]);
  std::swap(centres[1], centres[2]);
  const std::vector<Quad> quads = QuadsFromElements(centres);
  ASSERT_EQ(quads.size(), 1U);
  EXPECT_GT(SignedArea2(quads[0]), 0);
  // Blob centroids 0.3 px off move the extrapolated corners by up to about three times that.
  EXPECT_LT(WorstCornerError(quads[0], tag.corners), 2.0);
}

TEST(ClusterQuads, AStrayBlobBesideTheTagStillLeavesItsFourToPlaceIt) {
  const DimTag tag = MakeDimTag(35);
  std::vector<RedBlob> blobs = tag.blobs;
  const double a = 35 * CV_PI / 180;
  const cv::Point2d u(std::cos(a), std::sin(a)), v(-std::sin(a), std::cos(a));
  RedBlob element0 = blobs[0];
  element0.centroid = cv::Point2d(60.3, 58.8) - 7.0 * u - 7.0 * v;
  blobs.push_back(element0);
  RedBlob stray = blobs[0];
  stray.centroid = {100, 20};
  blobs.push_back(stray);
  BlobCluster cluster;
  cluster.blobs = {0, 4, 1, 3, 2};
  cluster.roi = cv::Rect(0, 0, tag.dark.cols, tag.dark.rows);
  const std::vector<Quad> quads = ClusterElementQuads(cluster, blobs, 20);
  EXPECT_LE(quads.size(), 5U);  // one per 4 of the 5 blobs
  int near = 0;
  for (const Quad& q : quads) near += WorstCornerError(q, tag.corners) < 2.0;
  EXPECT_EQ(near, 1);

  // Above kMaxBlobsForElementQuads the subsets are not tried.
  while (cluster.blobs.size() <= kMaxBlobsForElementQuads) {
    RedBlob more = stray;
    more.centroid.y += 10.0 * static_cast<double>(cluster.blobs.size());
    blobs.push_back(more);
    cluster.blobs.push_back(static_cast<int>(blobs.size()) - 1);
  }
  EXPECT_TRUE(ClusterElementQuads(cluster, blobs, 20).empty());
}

TEST(ClusterQuads, DegenerateBlobLayoutsPlaceNoSquare) {
  // Three in a row.
  EXPECT_TRUE(QuadsFromElements({{10, 10}, {20, 10}, {30, 10}}).empty());
  // A dart: the fourth blob inside the triangle of the others.
  EXPECT_TRUE(QuadsFromElements({{10, 10}, {40, 10}, {25, 40}, {25, 18}}).empty());
  // Tiny, or off the cluster's region: ClusterElementQuads drops them.
  const DimTag tag = MakeDimTag(0);
  std::vector<RedBlob> shrunk = tag.blobs;
  for (RedBlob& b : shrunk) {
    b.centroid = 0.1 * (b.centroid - cv::Point2d(60, 60)) + cv::Point2d(60, 60);
  }
  BlobCluster cluster;
  cluster.blobs = {0, 1, 2};
  cluster.roi = cv::Rect(0, 0, 120, 120);
  EXPECT_FALSE(ClusterElementQuads(cluster, tag.blobs, 20).empty());
  EXPECT_TRUE(ClusterElementQuads(cluster, shrunk, 20).empty());  // sides of about 3 px
  cluster.roi = cv::Rect(0, 0, 50, 50);
  EXPECT_TRUE(ClusterElementQuads(cluster, tag.blobs, 20).empty());  // outside the region
}

TEST(ClusterQuads, OtherBlobCountsPlaceNoSquare) {
  EXPECT_TRUE(QuadsFromElements({}).empty());
  EXPECT_TRUE(QuadsFromElements({{10, 10}, {20, 10}}).empty());
  EXPECT_TRUE(QuadsFromElements({{10, 10}, {20, 10}, {20, 20}, {10, 20}, {15, 15}}).empty());
}

}  // namespace
}  // namespace pintag::stage
