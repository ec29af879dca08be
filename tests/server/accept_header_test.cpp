// Content negotiation by Accept: the weights a client gives, not whether a media type's name
// appears in the header (which answered CSV to "text/csv;q=0").

#include "app/accept_header.hpp"

#include <gtest/gtest.h>

namespace pintag::app {
namespace {

TEST(AcceptQuality, TheMostSpecificRangeThatNamesATypeGivesItsWeight) {
  EXPECT_EQ(AcceptQuality("text/csv", "text/csv"), 1.0);
  EXPECT_EQ(AcceptQuality("text/csv", "application/json"), 0.0);
  EXPECT_EQ(AcceptQuality("text/csv;q=0", "text/csv"), 0.0);
  EXPECT_EQ(AcceptQuality("application/json;q=0.1, text/csv;q=0.5", "text/csv"), 0.5);
  EXPECT_EQ(AcceptQuality("application/json;q=0.1, text/csv;q=0.5", "application/json"), 0.1);
  // Case does not count, nor spaces around the parts.
  EXPECT_EQ(AcceptQuality("TEXT/CSV ; Q=0.7", "text/csv"), 0.7);
  // The type itself before type/*, before */*, whatever their order.
  EXPECT_EQ(AcceptQuality("*/*;q=0.2, text/*;q=0.4, text/csv;q=0.9", "text/csv"), 0.9);
  EXPECT_EQ(AcceptQuality("text/csv;q=0.9, */*;q=0.2", "application/json"), 0.2);
  EXPECT_EQ(AcceptQuality("text/*;q=0.3", "text/csv"), 0.3);
  EXPECT_EQ(AcceptQuality("text/*;q=0.3", "application/json"), 0.0);
  // Other parameters are passed over; a weight that is no weight counts as 1.
  EXPECT_EQ(AcceptQuality("text/csv;charset=utf-8;q=0.6", "text/csv"), 0.6);
  EXPECT_EQ(AcceptQuality("text/csv;q=high", "text/csv"), 1.0);
  EXPECT_EQ(AcceptQuality("text/csv;q=2", "text/csv"), 1.0);
  EXPECT_EQ(AcceptQuality("text/csv;q=nan", "text/csv"), 1.0);
  EXPECT_EQ(AcceptQuality("", "text/csv"), 0.0);
  EXPECT_EQ(AcceptQuality(",,;", "text/csv"), 0.0);
}

}  // namespace
}  // namespace pintag::app
