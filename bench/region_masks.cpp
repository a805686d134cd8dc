#include "region_masks.hpp"

#include <algorithm>
#include <cmath>

#include "dn/image/metrics.hpp"

namespace dn::bench {

Mask roughness_values_mask(const std::vector<float>& roughness, const std::vector<float>& values, float tolerance) {
  Mask mask(roughness.size(), 0);
  for (size_t i = 0; i < roughness.size(); ++i)
    for (float v : values)
      if (std::fabs(roughness[i] - v) <= tolerance) mask[i] = 1;
  return mask;
}

Mask glossy_mask(const std::vector<float>& roughness, float below) {
  Mask mask(roughness.size(), 0);
  for (size_t i = 0; i < roughness.size(); ++i) mask[i] = roughness[i] < below ? 1 : 0;
  return mask;
}

Mask highlight_mask(const float* rgb, int width, int height, float k, int dilate_px) {
  const size_t n = size_t(width) * size_t(height);
  std::vector<float> y(n);
  double mean = 0;
  for (size_t i = 0; i < n; ++i) {
    y[i] = image::linear_luminance(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
    if (std::isfinite(y[i])) mean += y[i];
  }
  if (n == 0) return {};
  mean /= double(n);
  std::vector<float> sorted = y;
  std::nth_element(sorted.begin(), sorted.begin() + long(n / 2), sorted.end());
  const double median = sorted[n / 2];
  const double threshold = double(k) * (median > 0 ? median : mean);
  Mask mask(n, 0);
  for (size_t i = 0; i < n; ++i) mask[i] = y[i] > threshold ? 1 : 0;
  return dilate(mask, width, height, dilate_px);
}

Mask disocclusion_mask(const std::vector<float>& motion, const std::vector<float>& depth,
                       const std::vector<float>& previous_depth, int width, int height, float tol) {
  Mask mask(size_t(width) * size_t(height), 0);
  auto agree = [tol](float a, float b) {
    if (std::isinf(a) || std::isinf(b)) return std::isinf(a) && std::isinf(b);
    if (!(a == a) || !(b == b)) return false;
    return std::fabs(a - b) <= tol * std::max(std::fabs(a), std::fabs(b));
  };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * size_t(width) + size_t(x);
      const float px = float(x) + 0.5f + motion[2 * i], py = float(y) + 0.5f + motion[2 * i + 1];
      if (!std::isfinite(px) || !std::isfinite(py) || px < 0 || py < 0 || px >= float(width) ||
          py >= float(height)) {
        mask[i] = 1;
        continue;
      }
      // The 2x2 pixels whose centres surround p_prev (a bilinear footprint;
      // taps of zero weight left out).
      const int x0 = int(std::floor(px - 0.5f)), y0 = int(std::floor(py - 0.5f));
      const float fx = px - 0.5f - float(x0), fy = py - 0.5f - float(y0);
      bool found = false;
      for (int dy = 0; dy < 2 && !found; ++dy)
        for (int dx = 0; dx < 2 && !found; ++dx) {
          const int tx = x0 + dx, ty = y0 + dy;
          if ((dx ? fx : 1.0f - fx) <= 0.0f || (dy ? fy : 1.0f - fy) <= 0.0f) continue;
          if (tx < 0 || ty < 0 || tx >= width || ty >= height) continue;
          found = agree(depth[i], previous_depth[size_t(ty) * size_t(width) + size_t(tx)]);
        }
      mask[i] = found ? 0 : 1;
    }
  return mask;
}

Mask dilate(const Mask& mask, int width, int height, int radius) {
  if (radius <= 0) return mask;
  // Separable: rows, then columns.
  Mask rows(mask.size(), 0), out(mask.size(), 0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      uint8_t v = 0;
      for (int t = std::max(0, x - radius); t <= std::min(width - 1, x + radius) && !v; ++t)
        v = mask[size_t(y) * size_t(width) + size_t(t)];
      rows[size_t(y) * size_t(width) + size_t(x)] = v;
    }
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      uint8_t v = 0;
      for (int t = std::max(0, y - radius); t <= std::min(height - 1, y + radius) && !v; ++t)
        v = rows[size_t(t) * size_t(width) + size_t(x)];
      out[size_t(y) * size_t(width) + size_t(x)] = v;
    }
  return out;
}

size_t count(const Mask& mask) {
  size_t c = 0;
  for (uint8_t v : mask) c += v ? 1 : 0;
  return c;
}

}  // namespace dn::bench
