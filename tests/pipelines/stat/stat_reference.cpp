#include "stat_reference.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace dn::test {
namespace {

bool finite(float x) { return std::isfinite(x); }
// Radiance: non-finite, negative or above 1e12 -> 0 (docs/pipelines.md "Sanitize rule").
float sanitize(float x) { return finite(x) && x <= 1e12f ? std::max(x, 0.0f) : 0.0f; }
// A normal with any non-finite component, or whose fp32 |n|^2 overflows, is
// the zero vector (docs/pipelines.md "Sanitize rule").
double normal_component(const std::vector<float>& n, int i, int c) {
  const double x = n[3 * i], y = n[3 * i + 1], z = n[3 * i + 2];
  const bool ok = finite(n[3 * i]) && finite(n[3 * i + 1]) && finite(n[3 * i + 2]) &&
                  x * x + y * y + z * z <= std::numeric_limits<float>::max();
  return ok ? static_cast<double>(n[3 * i + c]) : 0.0;
}

// An albedo guiding the filter: non-finite -> 0, then clamped to [0, 1e3].
double guide_albedo(float x) { return finite(x) ? std::clamp(static_cast<double>(x), 0.0, 1e3) : 0.0; }

}  // namespace

bool statistics_usable(float count, const float* mean, const float* m2, const float* m3) {
  const double n = count, y = 1999998.0;  // 2 sqrt(1e12) - 2
  if (!std::isfinite(count) || !(n > 0.0) || n > 16777216.0) return false;
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(mean[c]) || !std::isfinite(m2[c]) || !std::isfinite(m3[c])) return false;
    if (std::fabs(mean[c]) > y || m2[c] > n * y * y || std::fabs(m3[c]) > n * y * y * y) return false;
  }
  return true;
}

double guarded_albedo(float a) { return std::isfinite(a) && a >= 1e-3f && a <= 1e3f ? a : 1.0; }

double raw_from_moments(double n, double mean, double m2) {
  return (mean / 2.0 + 1.0) * (mean / 2.0 + 1.0) + std::max(m2, 0.0) / (4.0 * n);
}

double modulation(double radiance, double demodulated, float albedo) {
  return radiance > 0.0 && demodulated > 0.0 ? radiance / demodulated : guarded_albedo(albedo);
}

namespace {

// The count, Box-Cox means and M2 of the union of two pixels' samples, as
// stat.glsl's dn_stat_merge computes them in fp32 (M3 is not needed here).
struct Pooled {
  float n = 0.0f, mean[3] = {0, 0, 0}, m2[3] = {0, 0, 0};
};
void merge_into(Pooled& a, float n, const float* mean, const float* m2) {
  if (!(a.n > 0.0f)) {
    a.n = n;
    for (int c = 0; c < 3; ++c) a.mean[c] = mean[c], a.m2[c] = m2[c];
    return;
  }
  const float total = a.n + n, fb = n / total;
  for (int c = 0; c < 3; ++c) {
    const float d = mean[c] - a.mean[c];
    a.mean[c] = a.mean[c] + d * fb;
    a.m2[c] = a.m2[c] + m2[c] + d * d * (a.n * fb);
  }
  a.n = total;
}

}  // namespace

StatPrepared stat_prepare(const StatFrame& f, const StatParams& p) {
  const int n_px = f.width * f.height;
  StatPrepared r;
  r.theta.assign(4 * n_px, 0.0f);
  r.variance.assign(3 * n_px, 0.0f);
  constexpr float kFltEpsilon = 1.1920929e-7f;
  for (int i = 0; i < n_px; ++i) {
    const float n = f.count[i];
    const bool sampled = statistics_usable(n, &f.mean[3 * i], &f.m2[3 * i], &f.m3[3 * i]);
    if (sampled && n < 2.0f && p.pool_single) {
      const int x = i % f.width, y = i / f.width;
      // The merge of the usable statistics of the w x h block at (x0, y0), in row order.
      auto merged = [&](int x0, int y0, int bw, int bh) {
        Pooled m;
        for (int o = 0; o < bw * bh; ++o) {
          const int qx = x0 + o % bw, qy = y0 + o / bw, q = qy * f.width + qx;
          if (qx < 0 || qy < 0 || qx >= f.width || qy >= f.height) continue;
          if (statistics_usable(f.count[q], &f.mean[3 * q], &f.m2[3 * q], &f.m3[3 * q]))
            merge_into(m, f.count[q], &f.mean[3 * q], &f.m2[3 * q]);
        }
        return m;
      };
      // Per channel the second smallest sample variance of the 2x2 quadrants holding the pixel (2+ samples each).
      std::vector<std::array<float, 3>> quadrant;
      for (int k = 0; k < 4; ++k) {
        const Pooled m = merged(x - 1 + k % 2, y - 1 + k / 2, 2, 2);
        if (m.n >= 2.0f)
          quadrant.push_back({std::max(m.m2[0], 0.0f) / (m.n - 1.0f), std::max(m.m2[1], 0.0f) / (m.n - 1.0f),
                              std::max(m.m2[2], 0.0f) / (m.n - 1.0f)});
      }
      const Pooled window = merged(x - 1, y - 1, 3, 3);
      if (window.n >= 2.0f && !quadrant.empty()) {
        for (int c = 0; c < 3; ++c) {
          std::vector<float> v;
          for (const auto& q : quadrant) v.push_back(q[c]);
          std::sort(v.begin(), v.end());
          const float s2 = v[std::min<size_t>(1, v.size() - 1)];
          r.variance[3 * i + c] = std::max(s2 / n, static_cast<float>(p.variance_floor));
          r.theta[4 * i + c] = f.mean[3 * i + c];
        }
        r.theta[4 * i + 3] = window.n;
        continue;
      }
    }
    if (!sampled || n < 2.0f) {
      // A sample but no variance: the mean, for the single-sample test.
      if (!sampled) continue;  // n = 0 or out of bounds: no data
      for (int c = 0; c < 3; ++c) r.theta[4 * i + c] = f.mean[3 * i + c];
      r.theta[4 * i + 3] = n;
      continue;
    }
    for (int c = 0; c < 3; ++c) {
      const float s2 = std::max(f.m2[3 * i + c], 0.0f) / (n - 1.0f);
      r.variance[3 * i + c] = std::max(s2 / n, static_cast<float>(p.variance_floor));
      const float mu = f.mean[3 * i + c];
      r.theta[4 * i + c] = s2 > kFltEpsilon ? mu + (f.m3[3 * i + c] / n) / (6.0f * s2 * n) : mu;
    }
    r.theta[4 * i + 3] = n;
  }
  return r;
}

bool stat_member(float theta_p, float theta_q, float t2, float var_p, float var_q, bool asymmetric) {
  const float d = theta_p - theta_q, d2 = d * d;
  if (asymmetric) return d2 < var_p * (1.0f + 2.0f * t2) - var_q || d2 + var_p + var_q == 0.0f;
  return d2 <= t2 * (var_p + var_q);
}

StatResult stat_filter(const StatFrame& f, const StatPrepared& prep, const StatParams& p,
                       const std::vector<float>& t_squared, const std::vector<float>& still_t_squared) {
  const int w = f.width, h = f.height, r = p.radius;
  StatResult res;
  res.output.assign(3 * w * h, 0.0);
  res.members.assign(w * h, 0);
  res.rejected.assign(w * h, 0);
  // What pixel q contributes to an average: its raw mean, or the
  // demodulated mean from its moments (no statistics: the radiance).
  auto has_data = [&](int q) { return prep.theta[4 * q + 3] > 0.0f; };
  auto value = [&](int q, int c) {
    const double raw = sanitize(f.radiance[3 * q + c]);
    if (!p.demodulated || !has_data(q)) return raw;
    return raw_from_moments(f.count[q], f.mean[3 * q + c], f.m2[3 * q + c]);
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      double raw_p[3];
      for (int c = 0; c < 3; ++c) raw_p[c] = value(i, c);
      double sum[3] = {0, 0, 0}, weight_sum = 1.0;
      const float n_p = prep.theta[4 * i + 3];
      const bool single = n_p < 2.0f;  // gathers with the single-sample test
      const bool moving = !prep.moving.empty() && prep.moving[i];
      const bool asymmetric = p.asymmetric || moving;
      const bool kept = !prep.kept.empty() && prep.kept[i];
      // A pooled pixel's n_p is its window's count, not its own.
      const bool own_n = n_p == f.count[i];
      // Still, with statistics of its own: a pair of such is tested at still_alpha.
      auto still = [&](int k) {
        return prep.theta[4 * k + 3] >= 2.0f && prep.theta[4 * k + 3] == f.count[k] &&
               (prep.moving.empty() || !prep.moving[k]) && (prep.kept.empty() || !prep.kept[k]);
      };
      const float shrink_from = static_cast<float>(p.spatial_shrink_from);
      float sigma_spatial = static_cast<float>(p.sigma_spatial);
      int r_p = r;
      if (shrink_from > 0.0f && !moving && own_n && n_p > shrink_from) {
        sigma_spatial *= std::sqrt(shrink_from / n_p);
        r_p = std::min(r, static_cast<int>(std::ceil(3.0f * sigma_spatial)));
      }
      if (n_p > 0.0f && !kept) {
        for (int dy = -r_p; dy <= r_p; ++dy)
          for (int dx = -r_p; dx <= r_p; ++dx) {
            const int qx = x + dx, qy = y + dy, d2xy = dx * dx + dy * dy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h || d2xy > r_p * r_p || d2xy == 0) continue;
            const int q = qy * w + qx;
            if (prep.theta[4 * q + 3] < 2.0f) continue;
            const float n_q = prep.theta[4 * q + 3];
            const int nu = single ? std::max(static_cast<int>(n_q + 0.5f), 2) - 1 : static_cast<int>(n_p + n_q + 0.5f) - 2;
            const bool still_pair = still(i) && still(q) && !still_t_squared.empty();
            const std::vector<float>& table = still_pair ? still_t_squared : t_squared;
            const float t2 = table[std::min<size_t>(nu, table.size()) - 1];
            bool member = true;
            float share = 0.0f;  // the largest channel's d^2 over the test's bound
            for (int c = 0; c < 3; ++c) {
              // p without variance: its sample's variance is q's sample variance.
              const float var_p = single ? prep.variance[3 * q + c] * (n_q / n_p) : prep.variance[3 * i + c];
              const float var_q = prep.variance[3 * q + c];
              member = member && stat_member(prep.theta[4 * i + c], prep.theta[4 * q + c], t2, var_p, var_q, asymmetric);
              const float d = prep.theta[4 * i + c] - prep.theta[4 * q + c];
              const float bound = asymmetric ? var_p * (1.0f + 2.0f * t2) - var_q : t2 * (var_p + var_q);
              if (d * d > 0.0f) share = std::max(share, d * d / bound);
            }
            if (!member && !p.base_only) {
              ++res.rejected[i];
              continue;
            }
            const double membership =
                p.base_only || p.falloff == 0.0 ? 1.0 : std::pow(1.0 - std::min(share, 1.0f), p.falloff);
            ++res.members[i];
            double da2 = 0.0, dn2 = 0.0;
            for (int c = 0; c < 3; ++c) {
              // A non-finite albedo component guides as 0 (sanitize.glsl).
              const double da = guide_albedo(f.albedo[3 * i + c]) - guide_albedo(f.albedo[3 * q + c]);
              const double nn_p = normal_component(f.normal, i, c), nn_q = normal_component(f.normal, q, c);
              da2 += da * da;
              dn2 += (nn_p - nn_q) * (nn_p - nn_q);
            }
            const double wgt = membership * std::exp(-d2xy / (2.0 * sigma_spatial * sigma_spatial) -
                                        da2 / (2.0 * p.sigma_albedo * p.sigma_albedo) -
                                        dn2 / (2.0 * p.sigma_normal * p.sigma_normal));
            for (int c = 0; c < 3; ++c) sum[c] += wgt * (value(q, c) - raw_p[c]);
            weight_sum += wgt;
          }
      }
      for (int c = 0; c < 3; ++c) {
        const double average = raw_p[c] + sum[c] / weight_sum;
        const double m = has_data(i) ? modulation(sanitize(f.radiance[3 * i + c]), value(i, c), f.albedo[3 * i + c]) : 1.0;
        res.output[3 * i + c] = p.demodulated ? average * m : average;
      }
    }
  return res;
}

}  // namespace dn::test
