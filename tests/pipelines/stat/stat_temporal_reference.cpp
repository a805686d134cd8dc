#include "stat_temporal_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dn::test {
namespace {

bool finite(double x) { return std::isfinite(x); }
// The guide rules of docs/pipelines.md "Sanitize rule".
bool foreground(float z) { return std::isfinite(z) && z >= std::numeric_limits<float>::min() && z <= 1e18f; }

struct Vec3 {
  double x = 0, y = 0, z = 0;
};
double distance(const Vec3& a, const Vec3& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}
Vec3 normal_at(const std::vector<float>& n, int i) {
  const double x = n[3 * i], y = n[3 * i + 1], z = n[3 * i + 2];
  if (!finite(x) || !finite(y) || !finite(z) || x * x + y * y + z * z > std::numeric_limits<float>::max()) return {};
  return {x, y, z};
}

// Falcor's test: the same surface within 10 depth gradients and 16 normal gradients.
bool same_surface(double z, const Vec3& n, double grad_z, double grad_n, double z_prev, const Vec3& n_prev) {
  return std::abs(z - z_prev) / (grad_z + 0.01) <= 10.0 && distance(n, n_prev) / (grad_n + 0.01) <= 16.0;
}

StatAccumulator frame_statistics(const StatFrame& f, int q) {
  StatAccumulator s;
  s.n = f.count[q];
  const bool ok = statistics_usable(f.count[q], &f.mean[3 * q], &f.m2[3 * q], &f.m3[3 * q]);
  for (int c = 0; c < 3; ++c) {
    s.mean[c] = f.mean[3 * q + c];
    s.m2[c] = f.m2[3 * q + c];
    s.m3[c] = f.m3[3 * q + c];
    const float r = f.radiance[3 * q + c];
    s.raw[c] = std::isfinite(r) && r <= 1e12f ? std::max(r, 0.0f) : 0.0f;  // the radiance rule
  }
  return ok ? s : StatAccumulator{};
}

const double kPriorDof = 2.0;
// A pixel whose albedo is no reflectance (every component below 1e-3, one
// above 1.5, or not finite: a metal's diffuse colour) fades at this instead:
// moving, it keeps no history.
const double kUnexplainedFading = 0.0;
bool unexplained(const float* a) {
  const float m = std::max({a[0], a[1], a[2]});
  return !(m >= 1e-3f) || !(m <= 1.5f);
}
void theta_and_variance(const StatAccumulator& s, double theta[3], double var[3]) {
  for (int c = 0; c < 3; ++c) {
    const double s2 = std::max(s.m2[c], 0.0) / (s.n - 1.0);
    theta[c] = s2 > 1.1920929e-7 ? s.mean[c] + (s.m3[c] / s.n) / (6.0 * s2 * s.n) : s.mean[c];
    var[c] = s2 / s.n;
  }
}

}  // namespace

StatAccumulator stat_scale(StatAccumulator a, double f) {
  a.n *= f;
  for (int c = 0; c < 3; ++c) {
    a.m2[c] *= f;
    a.m3[c] *= f;
  }
  return a;
}

StatAccumulator stat_merge(const StatAccumulator& a, const StatAccumulator& b) {
  if (!(b.n > 0.0)) return a;
  if (!(a.n > 0.0)) return b;
  StatAccumulator r;
  r.n = a.n + b.n;
  for (int c = 0; c < 3; ++c) {
    const double d = b.mean[c] - a.mean[c];
    r.mean[c] = a.mean[c] + d * b.n / r.n;
    r.m2[c] = a.m2[c] + b.m2[c] + d * d * a.n * b.n / r.n;
    r.m3[c] = a.m3[c] + b.m3[c] + d * d * d * a.n * b.n * (a.n - b.n) / (r.n * r.n) +
              3.0 * d * (a.n * b.m2[c] - b.n * a.m2[c]) / r.n;
    r.raw[c] = (a.n * a.raw[c] + b.n * b.raw[c]) / r.n;
  }
  return r;
}

StatTemporalResult stat_temporal(const StatTemporalFrame& f, const StatTemporalState& prev, double fading,
                                 const std::vector<float>& t_squared) {
  const StatFrame& s = f.stats;
  const int w = s.width, h = s.height, n_px = w * h;
  const bool has_history = !f.reset && static_cast<int>(prev.acc.size()) == n_px;
  StatTemporalResult res;
  res.state.acc.assign(n_px, StatAccumulator{});
  res.state.depth.assign(n_px, 0.0f);
  res.state.normal.assign(3 * n_px, 0.0f);
  res.state.suspect.assign(n_px, 0);
  res.rejected.assign(n_px, 0);
  auto inside = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      const StatAccumulator current = frame_statistics(s, i);
      res.state.acc[i] = current;
      const float z = f.depth[i];
      const Vec3 n = normal_at(s.normal, i);
      if (!foreground(z) || (n.x == 0 && n.y == 0 && n.z == 0)) continue;
      res.state.depth[i] = z;
      res.state.normal[3 * i] = static_cast<float>(n.x);
      res.state.normal[3 * i + 1] = static_cast<float>(n.y);
      res.state.normal[3 * i + 2] = static_cast<float>(n.z);
      // Geometry gradients: per axis the smaller one-sided difference, then the max.
      double grad_z = 0.0, grad_n = 0.0;
      for (int axis = 0; axis < 2; ++axis) {
        double best_z = 1e30, best_n = 1e30;
        bool any = false;
        for (int side = -1; side <= 1; side += 2) {
          const int qx = x + (axis == 0 ? side : 0), qy = y + (axis == 1 ? side : 0);
          if (!inside(qx, qy) || !foreground(f.depth[qy * w + qx])) continue;
          any = true;
          best_z = std::min(best_z, std::abs(static_cast<double>(f.depth[qy * w + qx]) - z));
          best_n = std::min(best_n, distance(normal_at(s.normal, qy * w + qx), n));
        }
        if (any) {
          grad_z = std::max(grad_z, best_z);
          grad_n = std::max(grad_n, best_n);
        }
      }
      const double mvx = f.motion[2 * i], mvy = f.motion[2 * i + 1];
      if (!has_history || !finite(mvx) || !finite(mvy) || std::abs(mvx) > 1048576.0 || std::abs(mvy) > 1048576.0)
        continue;
      auto previous_on_surface = [&](int qx, int qy) {
        if (!inside(qx, qy)) return false;
        const int q = qy * w + qx;
        const Vec3 nq{prev.normal[3 * q], prev.normal[3 * q + 1], prev.normal[3 * q + 2]};
        return prev.depth[q] > 0.0f && same_surface(z, n, grad_z, grad_n, prev.depth[q], nq);
      };
      // Bilinear footprint of p_prev = p + mv.
      const double px = x + 0.5 + mvx - 0.5, py = y + 0.5 + mvy - 0.5;
      if (!(px > -1.0 && py > -1.0 && px < w && py < h)) continue;
      const int ox = static_cast<int>(std::floor(px)), oy = static_cast<int>(std::floor(py));
      const double tx = px - ox, ty = py - oy;
      const double weights[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
      double sum = 0.0;
      bool taken[4] = {false, false, false, false};
      for (int k = 0; k < 4; ++k)
        if (weights[k] > 0.0 && previous_on_surface(ox + (k & 1), oy + (k >> 1))) {
          taken[k] = true;
          sum += weights[k];
        }
      if (sum < 1e-3) continue;
      StatAccumulator history;
      for (int k = 0; k < 4; ++k)
        if (taken[k])
          history = stat_merge(history, stat_scale(prev.acc[(oy + (k >> 1)) * w + ox + (k & 1)], weights[k] / sum));
      const double stillness = std::clamp(1.0 - std::hypot(mvx, mvy) / 0.05, 0.0, 1.0);
      const double pixel_fading = unexplained(&s.albedo[3 * i]) ? kUnexplainedFading : fading;
      const double beta = pixel_fading + (1.0 - pixel_fading) * stillness;
      history = stat_scale(history, beta);
      if (!(history.n > 0.0)) continue;
      // The Welch test over the 3x3 windows around p_prev and p.
      const int cx = static_cast<int>(std::floor(x + 0.5 + mvx)), cy = static_cast<int>(std::floor(y + 0.5 + mvy));
      StatAccumulator hw, cw;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (previous_on_surface(cx + dx, cy + dy)) hw = stat_merge(hw, prev.acc[(cy + dy) * w + cx + dx]);
          const int qx = x + dx, qy = y + dy;
          if (!inside(qx, qy)) continue;
          const int q = qy * w + qx;
          if (foreground(f.depth[q]) && same_surface(z, n, grad_z, grad_n, f.depth[q], normal_at(s.normal, q)))
            cw = stat_merge(cw, frame_statistics(s, q));
        }
      hw = stat_scale(hw, beta);
      // Passes, fails (by more than t standard errors), or fails far (2t).
      int test = 0;
      if (hw.n >= 2.0 && cw.n >= 2.0) {
        double th[3], vh[3], tc[3], vc[3];
        theta_and_variance(hw, th, vh);
        theta_and_variance(cw, tc, vc);
        for (int c = 0; c < 3; ++c)  // the frame's sample variance shrunk toward the history's
          vc[c] = ((cw.n - 1.0) * vc[c] * cw.n + kPriorDof * vh[c] * hw.n) / (cw.n - 1.0 + kPriorDof) / cw.n;
        for (int c = 0; c < 3; ++c) {
          // Welch-Satterthwaite degrees of freedom (pooled when both variances are 0).
          const double den = vh[c] * vh[c] / (hw.n - 1.0) + vc[c] * vc[c] / (cw.n - 1.0);
          const double nu_real = den > 0.0 ? (vh[c] + vc[c]) * (vh[c] + vc[c]) / den : hw.n + cw.n - 2.0;
          const int nu = static_cast<int>(std::clamp(nu_real, 1.0, static_cast<double>(t_squared.size())));
          const double d2 = (th[c] - tc[c]) * (th[c] - tc[c]), bound = t_squared[nu - 1] * (vh[c] + vc[c]);
          if (d2 > 4.0 * bound) test = 2;
          else if (d2 > bound) test = std::max(test, 1);
        }
      }
      // Failing far rejects at once only where p moves (motion of 0.005 px or more).
      const bool was_suspect = inside(cx, cy) && prev.suspect[cy * w + cx] != 0;
      const bool far = test == 2 && !(std::hypot(mvx, mvy) < 0.005);
      if (far || (test != 0 && was_suspect)) {
        res.rejected[i] = 1;
      } else {
        res.state.acc[i] = stat_merge(history, current);
        res.state.suspect[i] = test != 0;
      }
    }
  return res;
}

}  // namespace dn::test
