// The header look at uploads (app/image_header.hpp), without a server: formats, claimed sizes,
// truncation, and JPEG structures that are whole though unusual.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "app/image_header.hpp"

namespace pintag::app {
namespace {

std::vector<std::uint8_t> Encode(const char* ext, int width, int height,
                                 const std::vector<int>& params = {}) {
  cv::Mat image(height, width, CV_8UC3);
  cv::randu(image, 0, 255);
  std::vector<std::uint8_t> bytes;
  cv::imencode(ext, image, bytes, params);
  return bytes;
}

TEST(ImageHeader, ReadsSizesOfWholeFiles) {
  for (const char* ext : {".jpg", ".png"}) {
    const ImageHeader h = InspectImage(Encode(ext, 321, 123));
    EXPECT_EQ(h.format, ext == std::string(".jpg") ? "jpeg" : "png");
    EXPECT_EQ(h.width, 321);
    EXPECT_EQ(h.height, 123);
    EXPECT_TRUE(h.complete) << h.problem;
  }
  const ImageHeader progressive =
      InspectImage(Encode(".jpg", 200, 100, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  EXPECT_TRUE(progressive.complete) << progressive.problem;
  EXPECT_EQ(progressive.width, 200);
  const ImageHeader restarts =
      InspectImage(Encode(".jpg", 200, 100, {cv::IMWRITE_JPEG_RST_INTERVAL, 2}));
  EXPECT_TRUE(restarts.complete) << restarts.problem;
}

TEST(ImageHeader, BytesAfterTheEndOfAJpegAreAllowed) {
  std::vector<std::uint8_t> jpeg = Encode(".jpg", 64, 64);
  jpeg.insert(jpeg.end(), 100, 0x55);  // some phones append data after EOI
  EXPECT_TRUE(InspectImage(jpeg).complete);
}

TEST(ImageHeader, EveryTruncationIsCaught) {
  for (const char* ext : {".jpg", ".png"}) {
    const std::vector<std::uint8_t> whole = Encode(ext, 64, 48);
    for (std::size_t n = 8; n + 1 < whole.size(); n += 7) {
      const ImageHeader h = InspectImage({whole.data(), n});
      EXPECT_FALSE(h.complete) << ext << " cut at " << n << " of " << whole.size();
      EXPECT_FALSE(h.problem.empty());
    }
  }
}

TEST(ImageHeader, OtherFormatsAndNonImages) {
  EXPECT_EQ(InspectImage(Encode(".tiff", 10, 10)).format, "tiff");
  const std::string text = "GIF89a not supported";
  EXPECT_EQ(InspectImage({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}).format,
            "");
  EXPECT_EQ(InspectImage({}).format, "");
}

}  // namespace
}  // namespace pintag::app
