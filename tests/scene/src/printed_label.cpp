// PrintedLabel: the held-out world's markers, on the label the dispatch counter prints. One label
// layout (pintag::label at 300 dpi) serves every marker, so PinTag, ArUco and AprilTag frames
// differ only in what fills the tag's place.

#include <apriltag/apriltag.h>
#include <apriltag/tag36h10.h>

#include <memory>
#include <mutex>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "pintag/codec/label.hpp"
#include "pintag/codec/palette.hpp"
#include "pintag/codec/tag_raster.hpp"
#include "pintag/scene/scene.hpp"

namespace pintag::scene {
namespace {

struct LabelTemplate {
  cv::Mat bgr;           ///< the label with its tag place left white
  LabelTagPixels place;  ///< the black square's pixels
};

cv::Mat ToMat(const RgbImage& image) {
  cv::Mat bgr(image.height, image.width, CV_8UC3);
  for (int y = 0; y < image.height; ++y) {
    auto* row = bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < image.width; ++x) {
      const Rgb8 c = image.at(x, y);
      row[x] = cv::Vec3b(c.b, c.g, c.r);
    }
  }
  return bgr;
}

// Rendered once per process: the label's text is the same on every frame (a detector must not
// care what the text says, only that there is text beside the tag).
const LabelTemplate& Template() {
  static const LabelTemplate label = [] {
    LabelContent content;
    content.pincode = Pincode(560001);
    content.key = TagKey(20301);
    content.office = "Bangalore G.P.O.";
    content.district = "Bengaluru";
    content.state = "Karnataka";
    content.bin = "56";
    content.plan = "default";
    const LabelOptions options;  // 100 × 150 mm, 300 dpi
    std::string error;
    const RgbImage raster = RenderLabelRaster(content, options, &error);
    if (!error.empty()) throw std::runtime_error("PrintedLabel: " + error);
    LabelTemplate t;
    t.bgr = ToMat(raster);
    t.place = TagPlacementPixels(options);
    const int quiet = QuietZonePx(t.place.square_side);
    const cv::Rect whole(t.place.square_x - quiet, t.place.square_y - quiet,
                         t.place.square_side + 2 * quiet, t.place.square_side + 2 * quiet);
    t.bgr(whole).setTo(cv::Scalar(255, 255, 255));
    return t;
  }();
  return label;
}

/// Binary cells (0 = black) drawn as the palette's black and white over exactly `side` pixels.
cv::Mat CellsToSquare(const cv::Mat& cells_u8, int side) {
  cv::Mat big;
  cv::resize(cells_u8, big, cv::Size(side, side), 0, 0, cv::INTER_NEAREST);
  const Rgb8 black = SrgbFor(PaletteColour::kBlack);
  cv::Mat bgr(big.size(), CV_8UC3, cv::Scalar(255, 255, 255));
  bgr.setTo(cv::Scalar(black.b, black.g, black.r), big < 128);
  return bgr;
}

cv::Mat ArucoSquare(int id, int side) {
  const cv::Ptr<cv::aruco::Dictionary> dictionary =
      cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_1000);
  if (id < 0 || id >= dictionary->bytesList.rows) {
    throw std::invalid_argument("PrintedLabel: ArUco id out of range");
  }
  cv::Mat cells;
  cv::aruco::drawMarker(dictionary, id, 7, cells, 1);
  return CellsToSquare(cells, side);
}

cv::Mat AprilTagSquare(int id, int side) {
  const std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> family(tag36h10_create(),
                                                                                tag36h10_destroy);
  if (id < 0 || id >= static_cast<int>(family->ncodes)) {
    throw std::invalid_argument("PrintedLabel: AprilTag id out of range");
  }
  const std::unique_ptr<image_u8_t, void (*)(image_u8_t*)> image(
      apriltag_to_image(family.get(), id), image_u8_destroy);
  const int n = family->width_at_border;
  const int offset = (family->total_width - n) / 2;
  cv::Mat cells(n, n, CV_8UC1);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      cells.at<std::uint8_t>(y, x) = image->buf[(y + offset) * image->stride + x + offset];
    }
  }
  return CellsToSquare(cells, side);
}

}  // namespace

MarkerTexture PrintedLabel(LabelMarker marker, int id) {
  const LabelTemplate& label = Template();
  const LabelTagPixels& place = label.place;
  MarkerTexture texture;
  texture.bgr = label.bgr.clone();
  const cv::Rect square(place.square_x, place.square_y, place.square_side, place.square_side);
  switch (marker) {
    case LabelMarker::kPinTag: {
      if (!TagKey::IsValid(id)) throw std::invalid_argument("PrintedLabel: key out of range");
      TagRasterOptions options;
      options.square_px = place.square_side;
      options.supersample = 2;
      const TagRaster raster = RenderTagRaster(TagKey(static_cast<std::uint16_t>(id)), options);
      const cv::Mat tag = ToMat(raster.image);
      tag(cv::Rect(raster.square_origin_px, raster.square_origin_px, raster.square_px,
                   raster.square_px))
          .copyTo(texture.bgr(square));
      break;
    }
    case LabelMarker::kAruco:
      ArucoSquare(id, place.square_side).copyTo(texture.bgr(square));
      break;
    case LabelMarker::kAprilTag:
      AprilTagSquare(id, place.square_side).copyTo(texture.bgr(square));
      break;
    case LabelMarker::kNone:
      break;
  }
  const double lo_x = place.square_x - 0.5, lo_y = place.square_y - 0.5;
  const double side = place.square_side;
  texture.square_corners_px = {cv::Point2d(lo_x, lo_y), cv::Point2d(lo_x + side, lo_y),
                               cv::Point2d(lo_x + side, lo_y + side),
                               cv::Point2d(lo_x, lo_y + side)};
  return texture;
}

}  // namespace pintag::scene
