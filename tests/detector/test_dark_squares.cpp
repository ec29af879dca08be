// Stage 3e: squares found by their darkness alone. Small tags are found, once each, with corners
// close to the truth; dark shapes without the four bright elements are not.

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "candidates/dark_squares.hpp"
#include "candidates/frame_scan.hpp"
#include "pintag/codec/geometry.hpp"
#include "synthetic.hpp"

namespace pintag::stage {
namespace {

cv::Mat DarkHalf(const cv::Mat& bgr) {
  FrameScanRequest request;
  request.dark_half = true;
  return ScanFrame(bgr, request).dark_half;
}

// Mean corner distance of `quad` to `truth`, over the four rotations of the corner order.
double CornerError(const Quad& quad, const std::array<cv::Point2d, 4>& truth) {
  double best = 1e9;
  for (int r = 0; r < 4; ++r) {
    double sum = 0;
    for (int i = 0; i < 4; ++i) sum += cv::norm(quad[(i + r) % 4] - truth[i]);
    best = std::min(best, sum / 4);
  }
  return best;
}

// The corner error of the square nearest the truth among `squares`.
double NearestCornerError(const std::vector<Quad>& squares,
                          const std::array<cv::Point2d, 4>& truth) {
  double best = 1e9;
  for (const Quad& q : squares) best = std::min(best, CornerError(q, truth));
  return best;
}

TEST(DarkSquares, FindsSmallTagsWithTheirCorners) {
  testing::SyntheticOptions options;
  options.blur_sigma = 0.8;
  options.noise_sigma = 2;
  const testing::SyntheticScene scene = MakeScene(
      {{.key = 100, .centre_px = {150, 150}, .square_px = 24},
       {.key = 200,
        .centre_px = {400, 150},
        .square_px = 32,
        .tilt_deg = 40,
        .tilt_axis_deg = 30,
        .roll_deg = 20},
       {.key = 300, .centre_px = {700, 300}, .square_px = 48, .tilt_deg = 55, .roll_deg = 70}},
      options);
  const std::vector<Quad> squares = FindDarkSquares(scene.bgr, DarkHalf(scene.bgr), {}, {});
  ASSERT_EQ(squares.size(), 3U);
  for (const testing::SyntheticTruth& truth : scene.truth) {
    EXPECT_LT(NearestCornerError(squares, truth.corners), 0.8) << "key " << truth.key;
  }
  // What a decoded tag covers is skipped, and only that: with the first tag decoded, the other
  // two are still found, and no square is returned in the first one's place.
  const cv::Point2d decoded = {150, 150};  // the first tag's centre
  const auto inside_decoded = [&](cv::Point2d p) { return cv::norm(p - decoded) < 16; };
  const std::vector<Quad> rest =
      FindDarkSquares(scene.bgr, DarkHalf(scene.bgr), {}, inside_decoded);
  EXPECT_EQ(rest.size(), 2U);
  for (const Quad& q : rest) {
    EXPECT_GT(cv::norm((q[0] + q[1] + q[2] + q[3]) / 4 - decoded), 16);
  }
}

// On a small square seen steeply the margins between the elements and the edge are a pixel or
// two wide, and blur fills them with the quiet zone's white: the refined pattern test reads as
// black only the margins that lie well inside the edge.
TEST(DarkSquares, FindsSteepSmallTagsWhoseMarginsTheBlurFills) {
  testing::SyntheticOptions options;
  options.blur_sigma = 1.6;
  options.noise_sigma = 2;
  const testing::SyntheticScene scene = MakeScene(
      {{.key = 400, .centre_px = {150, 150}, .square_px = 24, .tilt_deg = 60, .roll_deg = 10},
       {.key = 500,
        .centre_px = {400, 150},
        .square_px = 28,
        .tilt_deg = 65,
        .tilt_axis_deg = 45,
        .roll_deg = 30}},
      options);
  const std::vector<Quad> squares = FindDarkSquares(scene.bgr, DarkHalf(scene.bgr), {}, {});
  ASSERT_EQ(squares.size(), 2U);
  // Within the reach of the reader's own corner fit (reading/model_reader.hpp).
  for (const testing::SyntheticTruth& truth : scene.truth) {
    EXPECT_LT(NearestCornerError(squares, truth.corners), 1.5) << "key " << truth.key;
  }
}

TEST(DarkSquares, DarkShapesWithoutBrightElementsAreNot) {
  cv::Mat bgr(540, 960, CV_8UC3, cv::Scalar(235, 235, 235));
  // A plain black square, one with a single bright disk, one with a bright bar across it, and a
  // colourful square whose centre is as bright as its corners: each in a white margin.
  const std::array<cv::Point, 4> origins = {{{100, 100}, {300, 100}, {500, 100}, {700, 100}}};
  for (const cv::Point& o : origins)
    cv::rectangle(bgr, {o, o + cv::Point(40, 40)}, {20, 20, 20}, cv::FILLED);
  cv::circle(bgr, origins[1] + cv::Point(10, 10), 4, {40, 200, 120}, cv::FILLED);
  cv::rectangle(bgr, {origins[2] + cv::Point(4, 18), origins[2] + cv::Point(36, 22)},
                {40, 200, 120}, cv::FILLED);
  cv::rectangle(bgr, {origins[3] + cv::Point(6, 6), origins[3] + cv::Point(34, 34)}, {30, 160, 150},
                cv::FILLED);
  EXPECT_TRUE(FindDarkSquares(bgr, DarkHalf(bgr), {}, {}).empty());
}

// Where the margins lie far enough inside the edge (0.08 of a 52 px side: 4.2 px), they are still
// read: a square with the four bright elements and bright margins is refused, the same square
// with black margins is found.
TEST(DarkSquares, SquaresWhoseMarginsAreBrightAreNot) {
  constexpr int kSide = 52;
  cv::Mat bgr(300, 600, CV_8UC3, cv::Scalar(235, 235, 235));
  const std::array<cv::Point, 2> origins = {{{100, 100}, {400, 100}}};
  const cv::Scalar bright = {40, 200, 120};
  for (const cv::Point& o : origins) {
    cv::rectangle(bgr, {o, o + cv::Point(kSide, kSide)}, {20, 20, 20}, cv::FILLED);
    for (const geometry::Point& c : geometry::kElementCentres) {
      cv::circle(bgr, o + cv::Point(static_cast<int>(c.x * kSide), static_cast<int>(c.y * kSide)),
                 6, bright, cv::FILLED);
    }
  }
  // The second square's margin middles, each a bright dot 4 px inside its edge.
  const cv::Point second = origins[1];
  for (const cv::Point& m : {cv::Point(kSide / 2, 4), cv::Point(kSide - 4, kSide / 2),
                             cv::Point(kSide / 2, kSide - 4), cv::Point(4, kSide / 2)}) {
    cv::circle(bgr, second + m, 1, bright, cv::FILLED);
  }
  const std::vector<Quad> squares = FindDarkSquares(bgr, DarkHalf(bgr), {}, {});
  ASSERT_EQ(squares.size(), 1U);
  const cv::Point2d centre = (squares[0][0] + squares[0][1] + squares[0][2] + squares[0][3]) / 4;
  EXPECT_LT(cv::norm(centre - cv::Point2d(origins[0]) - cv::Point2d(kSide / 2., kSide / 2.)), 2);
}

}  // namespace
}  // namespace pintag::stage
