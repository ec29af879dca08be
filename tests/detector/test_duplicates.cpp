// RemoveDuplicates: one entry per place, and a decoded tag is never hidden by a rejected candidate
// listed before it (DetectorOptions::return_rejected).

#include <gtest/gtest.h>

#include "duplicates.hpp"

namespace pintag::stage {
namespace {

Detection At(double x, double y, double side, std::optional<int> key) {
  Detection d;
  d.corners = {Point2{x, y}, Point2{x + side, y}, Point2{x + side, y + side}, Point2{x, y + side}};
  d.square_px = side;
  if (key) d.key = TagKey(static_cast<std::uint16_t>(*key));
  if (!key) d.reject_reason = "no orientation fits the red quadrants";
  return d;
}

TEST(Duplicates, DecodedTagWinsOverARejectedCandidateListedFirst) {
  std::vector<Detection> list = {At(100, 100, 40, std::nullopt), At(102, 101, 41, 1234)};
  RemoveDuplicates(&list);
  ASSERT_EQ(list.size(), 1U);
  ASSERT_TRUE(list[0].key.has_value());
  EXPECT_EQ(list[0].key->value(), 1234);
}

TEST(Duplicates, FirstOfEachPlaceIsKeptAndOtherPlacesStay) {
  std::vector<Detection> list = {At(100, 100, 40, 7), At(103, 98, 40, 7), At(300, 100, 40, 9),
                                 At(300, 300, 40, std::nullopt), At(301, 302, 40, std::nullopt)};
  RemoveDuplicates(&list);
  ASSERT_EQ(list.size(), 3U);
  EXPECT_EQ(list[0].key->value(), 7);
  EXPECT_EQ(list[0].corners[0].x, 100);  // the first of the two at (100, 100)
  EXPECT_EQ(list[1].key->value(), 9);
  EXPECT_FALSE(list[2].key.has_value());
}

TEST(Duplicates, NeighboursFartherThanAQuarterSideAreDistinct) {
  // Two 40 px tags 12 px apart (more than 10 px, a quarter side) are two tags.
  std::vector<Detection> list = {At(100, 100, 40, 1), At(112, 100, 40, 2)};
  RemoveDuplicates(&list);
  EXPECT_EQ(list.size(), 2U);
}

}  // namespace
}  // namespace pintag::stage
