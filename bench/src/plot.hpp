#pragma once
// Line plots as PNG with cairo: one or more panels side by side sharing a legend, one line per
// series, y in percent.

#include <string>
#include <vector>

namespace pintag::bench {

struct PlotSeries {
  std::string name;
  std::vector<double> y;  ///< one value per x; NaN leaves a gap
};

struct PlotPanel {
  std::string title;
  std::vector<PlotSeries> series;
};

struct PlotSpec {
  std::string title;
  std::string subtitle;
  std::string x_label;
  std::string y_label = "recall (%)";
  std::vector<double> x;  ///< where the points are
  bool log_x = false;
  double y_min = 0;
  double y_max = 100;
  std::vector<PlotPanel> panels;
};

/// Writes `spec` to `path` (PNG). False with `error` set on failure.
bool WritePlot(const PlotSpec& spec, const std::string& path, std::string* error);

}  // namespace pintag::bench
