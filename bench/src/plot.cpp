#include "plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>

namespace pintag::bench {
namespace {

struct Style {
  double r, g, b;
  std::vector<double> dash;  ///< empty = solid
  int shape;                 ///< 0 circle, 1 square, 2 triangle, 3 diamond
};

// Colour-blind-safe (Okabe–Ito) colours, and a distinct dash and point shape for each series so
// the lines stay apart in grey print too.
const std::array<Style, 6> kStyles = {{
    {0.84, 0.37, 0.00, {}, 0},             // vermillion
    {0.00, 0.45, 0.70, {}, 1},             // blue
    {0.00, 0.62, 0.45, {7, 4}, 2},         // bluish green
    {0.80, 0.47, 0.65, {2, 3}, 3},         // reddish purple
    {0.90, 0.62, 0.00, {10, 3, 2, 3}, 0},  // orange
    {0.35, 0.35, 0.35, {4, 4}, 1},         // grey
}};

void Text(cairo_t* cr, const std::string& text, double x, double y, double size, double align_x,
          double align_y, bool bold = false) {
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, text.c_str(), &e);
  cairo_move_to(cr, x - e.x_bearing - align_x * e.width, y - e.y_bearing - align_y * e.height);
  cairo_show_text(cr, text.c_str());
}

double TextWidth(cairo_t* cr, const std::string& text, double size) {
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, text.c_str(), &e);
  return e.x_advance;
}

void Shape(cairo_t* cr, int shape, double x, double y, double r) {
  switch (shape) {
    case 0:
      cairo_new_sub_path(cr);
      cairo_arc(cr, x, y, r, 0, 2 * M_PI);
      break;
    case 1:
      cairo_rectangle(cr, x - r * 0.9, y - r * 0.9, 1.8 * r, 1.8 * r);
      break;
    case 2:
      cairo_move_to(cr, x, y - 1.2 * r);
      cairo_line_to(cr, x + 1.1 * r, y + 0.8 * r);
      cairo_line_to(cr, x - 1.1 * r, y + 0.8 * r);
      cairo_close_path(cr);
      break;
    default:
      cairo_move_to(cr, x, y - 1.3 * r);
      cairo_line_to(cr, x + 1.1 * r, y);
      cairo_line_to(cr, x, y + 1.3 * r);
      cairo_line_to(cr, x - 1.1 * r, y);
      cairo_close_path(cr);
      break;
  }
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

bool WritePlot(const PlotSpec& spec, const std::string& path, std::string* error) {
  const int panels = std::max<int>(1, static_cast<int>(spec.panels.size()));
  constexpr double kPanelW = 560, kPanelH = 400;
  constexpr double kLeft = 78, kRight = 24, kTop = 132, kBottom = 72, kGap = 40;
  const int width = static_cast<int>(kLeft + panels * kPanelW + (panels - 1) * kGap + kRight);
  const int height = static_cast<int>(kTop + kPanelH + kBottom);
  std::unique_ptr<cairo_surface_t, void (*)(cairo_surface_t*)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height), cairo_surface_destroy);
  std::unique_ptr<cairo_t, void (*)(cairo_t*)> context(cairo_create(surface.get()), cairo_destroy);
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  // Title, subtitle and the shared legend.
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  Text(cr, spec.title, width / 2.0, 14, 20, 0.5, 0, true);
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  Text(cr, spec.subtitle, width / 2.0, 44, 13, 0.5, 0);
  if (!spec.panels.empty()) {
    const auto& series = spec.panels.front().series;
    double total = 0;
    for (const auto& s : series) total += 46 + TextWidth(cr, s.name, 14) + 26;
    double x = (width - total) / 2;
    const double y = 82;
    for (std::size_t i = 0; i < series.size(); ++i) {
      const Style& st = kStyles[i % kStyles.size()];
      cairo_set_source_rgb(cr, st.r, st.g, st.b);
      cairo_set_line_width(cr, 2.5);
      cairo_set_dash(cr, st.dash.data(), static_cast<int>(st.dash.size()), 0);
      cairo_move_to(cr, x, y);
      cairo_line_to(cr, x + 38, y);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0);
      Shape(cr, st.shape, x + 19, y, 4.5);
      cairo_fill(cr);
      cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
      Text(cr, series[i].name, x + 46, y, 14, 0, 0.5);
      x += 46 + TextWidth(cr, series[i].name, 14) + 26;
    }
  }

  const double x_lo = spec.x.empty() ? 0 : *std::min_element(spec.x.begin(), spec.x.end());
  const double x_hi = spec.x.empty() ? 1 : *std::max_element(spec.x.begin(), spec.x.end());
  const auto fx = [&](double v) { return spec.log_x ? std::log(v) : v; };
  const double pad = 0.04 * (fx(x_hi) - fx(x_lo));
  const double ax_lo = fx(x_lo) - pad, ax_hi = fx(x_hi) + pad;

  for (int p = 0; p < panels; ++p) {
    const double left = kLeft + p * (kPanelW + kGap);
    const double top = kTop;
    const auto px = [&](double v) { return left + (fx(v) - ax_lo) / (ax_hi - ax_lo) * kPanelW; };
    const auto py = [&](double v) {
      return top + kPanelH - (v - spec.y_min) / (spec.y_max - spec.y_min) * kPanelH;
    };
    // Grid and ticks.
    cairo_set_line_width(cr, 1);
    for (int step = 0; spec.y_min + 10.0 * step <= spec.y_max + 1e-9; ++step) {
      const double v = spec.y_min + 10.0 * step;
      const bool major = std::fmod(v - spec.y_min, 20) < 1e-9;
      cairo_set_source_rgb(cr, major ? 0.85 : 0.93, major ? 0.85 : 0.93, major ? 0.85 : 0.93);
      cairo_move_to(cr, left, std::round(py(v)) + 0.5);
      cairo_line_to(cr, left + kPanelW, std::round(py(v)) + 0.5);
      cairo_stroke(cr);
      if (major) {
        cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
        Text(cr, Number(v), left - 8, py(v), 13, 1, 0.5);
      }
    }
    for (double v : spec.x) {
      cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
      cairo_move_to(cr, std::round(px(v)) + 0.5, top);
      cairo_line_to(cr, std::round(px(v)) + 0.5, top + kPanelH);
      cairo_stroke(cr);
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      cairo_move_to(cr, std::round(px(v)) + 0.5, top + kPanelH);
      cairo_line_to(cr, std::round(px(v)) + 0.5, top + kPanelH + 5);
      cairo_stroke(cr);
      Text(cr, Number(v), px(v), top + kPanelH + 9, 13, 0.5, 0);
    }
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_set_line_width(cr, 1.2);
    cairo_rectangle(cr, left + 0.5, top + 0.5, kPanelW, kPanelH);
    cairo_stroke(cr);
    // Axis labels and the panel's title.
    Text(cr, spec.x_label, left + kPanelW / 2, top + kPanelH + 36, 14, 0.5, 0);
    if (p == 0) {
      cairo_save(cr);
      cairo_translate(cr, 20, top + kPanelH / 2);
      cairo_rotate(cr, -M_PI / 2);
      Text(cr, spec.y_label, 0, 0, 14, 0.5, 0.5);
      cairo_restore(cr);
    }
    if (p < static_cast<int>(spec.panels.size())) {
      cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
      Text(cr, spec.panels[p].title, left + kPanelW / 2, top - 10, 15, 0.5, 1, true);
      // The lines, clipped to the panel.
      cairo_save(cr);
      cairo_rectangle(cr, left, top - 8, kPanelW, kPanelH + 16);
      cairo_clip(cr);
      const auto& series = spec.panels[p].series;
      for (std::size_t i = 0; i < series.size(); ++i) {
        const Style& st = kStyles[i % kStyles.size()];
        cairo_set_source_rgb(cr, st.r, st.g, st.b);
        cairo_set_line_width(cr, 2.5);
        cairo_set_dash(cr, st.dash.data(), static_cast<int>(st.dash.size()), 0);
        bool pen_down = false;
        for (std::size_t k = 0; k < spec.x.size() && k < series[i].y.size(); ++k) {
          const double v = series[i].y[k];
          if (std::isnan(v)) {
            pen_down = false;
            continue;
          }
          if (pen_down) {
            cairo_line_to(cr, px(spec.x[k]), py(v));
          } else {
            cairo_move_to(cr, px(spec.x[k]), py(v));
          }
          pen_down = true;
        }
        cairo_stroke(cr);
        cairo_set_dash(cr, nullptr, 0, 0);
        for (std::size_t k = 0; k < spec.x.size() && k < series[i].y.size(); ++k) {
          if (std::isnan(series[i].y[k])) continue;
          Shape(cr, st.shape, px(spec.x[k]), py(series[i].y[k]), 4.5);
          cairo_fill(cr);
        }
      }
      cairo_restore(cr);
    }
  }
  cairo_surface_flush(surface.get());
  if (cairo_surface_write_to_png(surface.get(), path.c_str()) != CAIRO_STATUS_SUCCESS) {
    *error = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace pintag::bench
