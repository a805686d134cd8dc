#include "accumulate_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dn::test {

AccumulateReference::AccumulateReference(int width, int height, AccumulateParams params)
    : w_(width), h_(height), p_(params), colour_(4 * width * height, 0.0), geometry_(4 * width * height, 0.0) {}

std::vector<double> AccumulateReference::step(const ReferenceFrame& f) {
  const int n = w_ * h_;
  std::vector<double> out(3 * n);
  std::vector<double> colour(4 * n), geometry(4 * n);
  const bool reset = f.reset || !has_history_;

  for (int y = 0; y < h_; ++y) {
    for (int x = 0; x < w_; ++x) {
      const int i = y * w_ + x;
      // Sanitize radiance: non-finite, negative or above 1e12 components become 0.
      double c[3];
      for (int k = 0; k < 3; ++k) {
        const double v = f.radiance[3 * i + k];
        c[k] = (std::isfinite(v) && v > 0.0 && v <= 1e12f) ? v : 0.0;
      }
      const double z = f.depth[i];
      // Foreground within [FLT_MIN, 1e18] (docs/pipelines.md "Sanitize rule").
      const bool foreground = std::isfinite(z) && z >= std::numeric_limits<float>::min() && z <= 1e18;
      if (!foreground) {
        for (int k = 0; k < 3; ++k) out[3 * i + k] = colour[4 * i + k] = c[k];
        colour[4 * i + 3] = 0.0;
        for (int k = 0; k < 4; ++k) geometry[4 * i + k] = 0.0;
        continue;
      }
      double nrm[3];
      // A normal whose fp32 |n|^2 would overflow counts as none, like a non-finite one.
      const double n2 = f.normal[3 * i] * f.normal[3 * i] + f.normal[3 * i + 1] * f.normal[3 * i + 1] +
                        f.normal[3 * i + 2] * f.normal[3 * i + 2];
      const bool normal_ok = std::isfinite(f.normal[3 * i]) && std::isfinite(f.normal[3 * i + 1]) &&
                             std::isfinite(f.normal[3 * i + 2]) && n2 <= std::numeric_limits<float>::max();
      for (int k = 0; k < 3; ++k) nrm[k] = normal_ok ? f.normal[3 * i + k] : 0.0;
      const double mvx = f.motion[2 * i], mvy = f.motion[2 * i + 1];

      double prev[3] = {0, 0, 0};
      double prev_len = 0.0;
      // Motion beyond 2^20 px is none.
      if (!reset && std::isfinite(mvx) && std::isfinite(mvy) && std::fabs(mvx) <= 1048576.0 &&
          std::fabs(mvy) <= 1048576.0) {
        // Position in the previous frame, in pixel units with centres at +0.5.
        const double px = x + 0.5 + mvx - 0.5;
        const double py = y + 0.5 + mvy - 0.5;
        if (px > -1.0 && py > -1.0 && px < w_ && py < h_) {
          const double bx = std::floor(px), by = std::floor(py);
          const double tx = px - bx, ty = py - by;
          double sum_c[3] = {0, 0, 0}, sum_len = 0.0, sum_w = 0.0;
          for (int dy = 0; dy <= 1; ++dy) {
            for (int dx = 0; dx <= 1; ++dx) {
              const int qx = static_cast<int>(bx) + dx, qy = static_cast<int>(by) + dy;
              if (qx < 0 || qy < 0 || qx >= w_ || qy >= h_) continue;
              const int q = qy * w_ + qx;
              const double zp = geometry_[4 * q + 3];
              if (!(zp > 0.0)) continue;
              if (!(std::fabs(z - zp) / std::max(z, zp) < p_.depth_tolerance)) continue;
              const double d = nrm[0] * geometry_[4 * q] + nrm[1] * geometry_[4 * q + 1] + nrm[2] * geometry_[4 * q + 2];
              if (!(d > p_.normal_threshold)) continue;
              const double wgt = (dx ? tx : 1.0 - tx) * (dy ? ty : 1.0 - ty);
              for (int k = 0; k < 3; ++k) sum_c[k] += wgt * colour_[4 * q + k];
              sum_len += wgt * colour_[4 * q + 3];
              sum_w += wgt;
            }
          }
          if (sum_w >= 1e-3) {
            for (int k = 0; k < 3; ++k) prev[k] = sum_c[k] / sum_w;
            prev_len = sum_len / sum_w;
          }
        }
      }
      const double len = std::min(prev_len + 1.0, p_.max_history);
      const double alpha = std::max(1.0 / len, p_.alpha_min);
      for (int k = 0; k < 3; ++k) {
        const double v = prev[k] * (1.0 - alpha) + c[k] * alpha;
        out[3 * i + k] = colour[4 * i + k] = v;
      }
      colour[4 * i + 3] = len;
      for (int k = 0; k < 3; ++k) geometry[4 * i + k] = nrm[k];
      geometry[4 * i + 3] = z;
    }
  }
  colour_ = std::move(colour);
  geometry_ = std::move(geometry);
  has_history_ = true;
  return out;
}

}  // namespace dn::test
