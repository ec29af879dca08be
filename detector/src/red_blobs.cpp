#include "red_blobs.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

namespace pintag::stage {

std::vector<RedBlob> FindRedBlobs(const cv::Mat& mask, const BlobLimits& limits) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<RedBlob> blobs;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < limits.min_area || area > limits.max_area) continue;
    const cv::Rect box(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                       stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
    const double cx = centroids.at<double>(i, 0), cy = centroids.at<double>(i, 1);
    // Second central moments over this component's pixels only.
    double sxx = 0, syy = 0, sxy = 0;
    for (int y = box.y; y < box.y + box.height; ++y) {
      const int* row = labels.ptr<int>(y);
      const double dy = y - cy;
      for (int x = box.x; x < box.x + box.width; ++x) {
        if (row[x] != i) continue;
        const double dx = x - cx;
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
      }
    }
    sxx = sxx / area + 1.0 / 12;  // a pixel is a unit square, not a point
    syy = syy / area + 1.0 / 12;
    sxy /= area;
    const double mean = (sxx + syy) / 2;
    const double diff = std::sqrt(std::max(0.0, (sxx - syy) * (sxx - syy) / 4 + sxy * sxy));
    const double l1 = mean + diff, l2 = std::max(mean - diff, 1e-6);
    RedBlob blob;
    blob.centroid = {cx, cy};
    blob.area = area;
    blob.major = 4 * std::sqrt(l1);  // an ellipse with semi-axis a has variance a²/4
    blob.minor = 4 * std::sqrt(l2);
    blob.fill = area / (std::numbers::pi / 4 * blob.major * blob.minor);
    blob.box = box;
    if (blob.fill < limits.min_fill || blob.fill > 1.0 / limits.min_fill) continue;
    if (blob.major > limits.max_elongation * blob.minor) continue;
    blobs.push_back(blob);
  }
  if (static_cast<int>(blobs.size()) > limits.max_blobs) {
    std::nth_element(blobs.begin(), blobs.begin() + limits.max_blobs, blobs.end(),
                     [](const RedBlob& a, const RedBlob& b) { return a.area > b.area; });
    blobs.resize(limits.max_blobs);
  }
  return blobs;
}

}  // namespace pintag::stage
