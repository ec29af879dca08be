#include "reading/psf.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pintag::reading {
namespace {

constexpr int kSide = 2 * kMaxKernelRadius + 2;  // dense kernels: offsets −R … R + 1
constexpr double kDropBelow = 1.5e-3;            // taps this small (of the peak) are left out

constexpr int kDenseTaps = kSide * kSide;

// Where offset (dx, dy) sits in a dense kernel's row-major taps.
std::size_t DenseIndex(int dx, int dy) {
  const int i = (dy + kMaxKernelRadius) * kSide + dx + kMaxKernelRadius;
  return static_cast<std::size_t>(i);
}

struct Dense {
  std::vector<double> w = std::vector<double>(static_cast<std::size_t>(kDenseTaps), 0.0);
  double& at(int dx, int dy) { return w[DenseIndex(dx, dy)]; }
  double at(int dx, int dy) const { return w[DenseIndex(dx, dy)]; }
};

// A round Gaussian of `minor` swept evenly along a line so that the spread along it is `major`
// (weights along the line by erf), centred on (cx, cy) relative to the anchor pixel.
Dense Smear(double major, double minor, double angle_deg, double cx, double cy) {
  Dense d;
  const double angle = angle_deg * std::numbers::pi / 180;
  const double c = std::cos(angle), s = std::sin(angle);
  const double sigma = std::max(minor, 0.2);
  const double half_line = std::sqrt(3 * std::max(0.0, major * major - sigma * sigma));
  const double to_erf = 1 / (std::numbers::sqrt2 * sigma);
  double total = 0;
  for (int dy = -kMaxKernelRadius; dy <= kMaxKernelRadius + 1; ++dy) {
    for (int dx = -kMaxKernelRadius; dx <= kMaxKernelRadius + 1; ++dx) {
      const double x = dx - cx, y = dy - cy;
      const double along = c * x + s * y, across = -s * x + c * y;
      double w = std::exp(-0.5 * across * across / (sigma * sigma));
      if (half_line > 1e-6) {
        w *= std::erf((along + half_line) * to_erf) - std::erf((along - half_line) * to_erf);
      } else {
        w *= std::exp(-0.5 * along * along / (sigma * sigma));
      }
      d.at(dx, dy) = w;
      total += w;
    }
  }
  for (double& w : d.w) w /= total;
  return d;
}

// `d` blurred by a round Gaussian of `sigma` (separably, within the dense window).
Dense Blurred(const Dense& d, double sigma) {
  const int reach = std::min(kMaxKernelRadius, static_cast<int>(std::ceil(3 * sigma)));
  const int taps = 2 * reach + 1;
  std::vector<double> g(static_cast<std::size_t>(taps));
  double total = 0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    const double i = static_cast<double>(k) - reach;
    g[k] = std::exp(-0.5 * i * i / (sigma * sigma));
    total += g[k];
  }
  for (double& v : g) v /= total;
  const auto weight = [&](int i) {  // the tap at offset i, −reach … reach
    const int k = i + reach;
    return g[static_cast<std::size_t>(k)];
  };
  Dense rows, out;
  const auto inside = [](int v) { return v >= -kMaxKernelRadius && v <= kMaxKernelRadius + 1; };
  for (int dy = -kMaxKernelRadius; dy <= kMaxKernelRadius + 1; ++dy) {
    for (int dx = -kMaxKernelRadius; dx <= kMaxKernelRadius + 1; ++dx) {
      double sum = 0;
      for (int i = -reach; i <= reach; ++i) {
        if (inside(dx - i)) sum += weight(i) * d.at(dx - i, dy);
      }
      rows.at(dx, dy) = sum;
    }
  }
  for (int dy = -kMaxKernelRadius; dy <= kMaxKernelRadius + 1; ++dy) {
    for (int dx = -kMaxKernelRadius; dx <= kMaxKernelRadius + 1; ++dx) {
      double sum = 0;
      for (int i = -reach; i <= reach; ++i) {
        if (inside(dy - i)) sum += weight(i) * rows.at(dx, dy - i);
      }
      out.at(dx, dy) = sum;
    }
  }
  return out;
}

Kernel ToRows(const Dense& d) {
  double peak = 0;
  for (const double w : d.w) peak = std::max(peak, std::abs(w));
  Kernel rows;
  for (int dy = -kMaxKernelRadius; dy <= kMaxKernelRadius + 1; ++dy) {
    int first = 1 << 20, last = -(1 << 20);
    for (int dx = -kMaxKernelRadius; dx <= kMaxKernelRadius + 1; ++dx) {
      if (std::abs(d.at(dx, dy)) >= kDropBelow * peak) first = std::min(first, dx), last = dx;
    }
    if (first > last) continue;
    KernelRow row;
    row.dy = dy;
    row.dx_begin = first;
    for (int dx = first; dx <= last; ++dx) {
      const double w = d.at(dx, dy);
      row.weight.push_back(std::abs(w) >= kDropBelow * peak ? w : 0.0);
    }
    row.prefix.assign(row.weight.size() + 1, 0.0);
    for (std::size_t j = 0; j < row.weight.size(); ++j) {
      row.prefix[j + 1] = row.prefix[j] + row.weight[j];
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

Kernel MakeKernel(const LumaBlur& blur) {
  const Dense base = Smear(blur.major, blur.minor, blur.angle_deg, 0, 0);
  if (blur.sharpen <= 0) return ToRows(base);
  const Dense wide = Blurred(base, blur.sharpen_sigma);
  Dense sharp;
  for (std::size_t i = 0; i < sharp.w.size(); ++i) {
    sharp.w[i] = (1 + blur.sharpen) * base.w[i] - blur.sharpen * wide.w[i];
  }
  return ToRows(sharp);
}

Kernel MakeKernel(const ChromaBlur& blur) {
  // The mean over the block's four pixels (anchor + (bx, by)) of the Gaussian around each.
  const Dense g = Smear(blur.sigma, blur.sigma, 0, 0, 0);
  Dense box;
  for (int dy = -kMaxKernelRadius; dy <= kMaxKernelRadius + 1; ++dy) {
    for (int dx = -kMaxKernelRadius; dx <= kMaxKernelRadius + 1; ++dx) {
      double sum = 0;
      for (int by = 0; by <= 1; ++by) {
        for (int bx = 0; bx <= 1; ++bx) {
          const int x = dx - bx, y = dy - by;
          if (x >= -kMaxKernelRadius && x <= kMaxKernelRadius + 1 && y >= -kMaxKernelRadius &&
              y <= kMaxKernelRadius + 1) {
            sum += 0.25 * g.at(x, y);
          }
        }
      }
      box.at(dx, dy) = sum;
    }
  }
  return ToRows(box);
}

}  // namespace pintag::reading
