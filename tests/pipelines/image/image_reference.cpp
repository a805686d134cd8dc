#include "image_reference.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace dn::test {
namespace {

using Vec3 = std::array<double, 3>;

bool finite(double x) { return std::isfinite(x); }
double luminance(const Vec3& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

double sanitize_radiance(double x) { return finite(x) && x <= 1e12 ? std::max(x, 0.0) : 0.0; }
double guarded_albedo(double a) { return finite(a) && a >= 1e-3 && a <= 1e3 ? a : 1.0; }
bool foreground(double z) { return finite(z) && z >= 1.17549435e-38 && z <= 1e18; }

struct Pixel {
  Vec3 albedo{1.0, 1.0, 1.0};  // the guarded albedo (1 without a plane)
  Vec3 normal{0.0, 0.0, 0.0};
  double depth = 0.0;
};

// The frame's noise gain: the histogram's median t, interpolated within its
// bin, over the median of a chi-square variable of one degree (0.4549).
double median_gain(const std::vector<double>& histogram) {
  double total = 0.0;
  for (double c : histogram) total += c;
  if (total == 0.0) return 0.0;
  double below = 0.0;
  size_t b = 0;
  for (; b + 1 < histogram.size() && below + histogram[b] < 0.5 * total; ++b) below += histogram[b];
  const double within = histogram[b] > 0.0 ? (0.5 * total - below) / histogram[b] : 0.5;
  return std::exp2(-24.0 + (double(b) + within) / 8.0) / 0.4549364;
}

class Image {
 public:
  Image(int w, int h, const ImageFrame& f, const ImageParams& p) : w_(w), h_(h), f_(f), p_(p), px_(size_t(w) * h) {
    for (int i = 0; i < w * h; ++i) {
      Pixel& q = px_[i];
      if (!f.albedo.empty())
        for (int k = 0; k < 3; ++k) q.albedo[k] = guarded_albedo(f.albedo[3 * i + k]);
      if (!f.normal.empty()) {
        const Vec3 n{f.normal[3 * i], f.normal[3 * i + 1], f.normal[3 * i + 2]};
        const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (finite(n[0]) && finite(n[1]) && finite(n[2]) && finite(nn)) q.normal = n;
      }
      if (!f.depth.empty() && foreground(f.depth[i])) q.depth = f.depth[i];
    }
  }

  Vec3 demodulated(int i) const {
    Vec3 c;
    for (int k = 0; k < 3; ++k) c[k] = sanitize_radiance(f_.radiance[3 * i + k]) / px_[i].albedo[k];
    return c;
  }

  double geometry_weight(int p, int q, double dist) const {
    double w = 1.0;
    if (!f_.normal.empty()) {
      const Vec3 &a = px_[p].normal, &b = px_[q].normal;
      w *= std::pow(std::max(0.0, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]), p_.phi_normal);
    }
    if (!f_.depth.empty()) {
      const double zp = px_[p].depth, zq = px_[q].depth;
      if ((zp > 0.0) != (zq > 0.0)) return 0.0;
      if (zp > 0.0) w *= std::exp(-std::abs(zp - zq) / (p_.phi_depth * dist * zp));
    }
    if (!f_.albedo.empty()) {
      double d = 0.0;
      for (int k = 0; k < 3; ++k) d += std::abs(px_[p].albedo[k] - px_[q].albedo[k]);
      w *= std::exp(-d / p_.phi_albedo);
    }
    return w;
  }

  int at(int x, int y) const { return y * w_ + x; }
  int clamped(int x, int y) const { return at(std::clamp(x, 0, w_ - 1), std::clamp(y, 0, h_ - 1)); }
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < w_ && y < h_; }

  std::vector<double> run() const {
    const int n = w_ * h_;
    // The residual of each pixel's luminance against its 4 neighbours' mean.
    std::vector<double> r(n);
    std::vector<Vec3> colour(n);
    std::vector<double> histogram(256, 0.0);  // of t = r^2 / (1.25 m^2), eighths of an octave from 2^-24
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        const int i = at(x, y);
        colour[i] = demodulated(i);
        const double around = luminance(demodulated(clamped(x + 1, y))) + luminance(demodulated(clamped(x - 1, y))) +
                              luminance(demodulated(clamped(x, y + 1))) + luminance(demodulated(clamped(x, y - 1)));
        const double l = luminance(colour[i]);
        r[i] = l - 0.25 * around;
        const double m = 0.2 * (l + around), t = r[i] * r[i] / (1.25 * m * m);
        if (m > 0.0 && t > 0.0 && finite(t))
          ++histogram[size_t(std::clamp(std::floor((std::log2(t) + 24.0) * 8.0), 0.0, 255.0))];
      }
    const double gain = median_gain(histogram);
    // The noise variance over the 5x5 taps q on p's surface (guide weight >=
    // 1/2): the median of r_q^2 over 0.4549 and 1.25, or (noise_estimate 1) with
    // a = mean r_q^2 / 1.25 and b = max(0, mean(r_q^2 - r_q (r_right + r_lower) / 2)) / 1.75
    // (neighbours clamped to the frame) b min(1, b / a)^3; at most noise_cap times
    // the gain times the squared weighted mean luminance.
    std::vector<double> noise(n);
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        const int p = at(x, y);
        double mean = 0.0, weight = 0.0, plain = 0.0, decorrelated = 0.0;
        std::vector<double> own;  // squared residuals of the taps on p's surface
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) {
            if (!inside(x + dx, y + dy)) continue;
            const int q = at(x + dx, y + dy);
            const double w = dx == 0 && dy == 0 ? 1.0 : geometry_weight(p, q, std::hypot(dx, dy));
            mean += w * luminance(colour[q]);
            weight += w;
            if (w < 0.5) continue;
            const double right = r[clamped(x + dx + 1, y + dy)], lower = r[clamped(x + dx, y + dy + 1)];
            own.push_back(r[q] * r[q]);
            plain += r[q] * r[q];
            decorrelated += r[q] * r[q] - 0.5 * r[q] * (right + lower);
          }
        std::sort(own.begin(), own.end());
        const double m = mean / weight, taps = double(own.size());
        const double a = plain / (1.25 * taps), b = std::max(decorrelated, 0.0) / (1.75 * taps);
        const double local = !p_.decorrelated_noise ? own[own.size() / 2] / 0.4549364 / 1.25
                             : a > 0.0            ? b * std::pow(std::min(1.0, b / a), 3.0)
                                                  : 0.0;
        noise[p] = p_.noise_cap > 0.0 ? std::min(local, p_.noise_cap * gain * m * m) : local;
      }
    // The a-trous iterations.
    const double h[3] = {3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0};
    std::vector<Vec3> c = colour;
    std::vector<double> var = noise;
    for (int it = 0; it < p_.iterations; ++it) {
      const int step = 1 << it;
      std::vector<Vec3> nc(n);
      std::vector<double> nv(n);
      for (int y = 0; y < h_; ++y)
        for (int x = 0; x < w_; ++x) {
          const int p = at(x, y);
          const double sigma = std::sqrt(std::max(var[p], 0.0));
          if (!(sigma > 0.0)) {
            nc[p] = c[p];
            nv[p] = 0.0;
            continue;
          }
          const double lp = luminance(c[p]);
          const double centre = h[0] * h[0];
          Vec3 sum{centre * c[p][0], centre * c[p][1], centre * c[p][2]};
          double vsum = centre * centre * var[p], weight = centre;
          for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
              if (dx == 0 && dy == 0) continue;
              const int qx = x + dx * step, qy = y + dy * step;
              if (!inside(qx, qy)) continue;
              const int q = at(qx, qy);
              const double w = h[std::abs(dx)] * h[std::abs(dy)] * geometry_weight(p, q, step * std::hypot(dx, dy)) *
                               std::exp(-std::abs(lp - luminance(c[q])) /
                                        std::max(p_.phi_luminance * std::sqrt(std::max(std::min(var[p], var[q]), 0.0)),
                                                 1e-30));
              for (int k = 0; k < 3; ++k) sum[k] += w * c[q][k];
              vsum += w * w * var[q];
              weight += w;
            }
          for (int k = 0; k < 3; ++k) nc[p][k] = sum[k] / weight;
          nv[p] = vsum / (weight * weight);
        }
      c.swap(nc);
      var.swap(nv);
    }
    // The guard and the remodulation.
    std::vector<double> out(3 * size_t(n));
    for (int i = 0; i < n; ++i) {
      const double reach = p_.harm_guard * std::sqrt(std::max(noise[i], 0.0));
      for (int k = 0; k < 3; ++k) {
        double v = c[i][k];
        if (p_.harm_guard > 0.0) v = colour[i][k] + std::clamp(v - colour[i][k], -reach, reach);
        out[3 * i + k] = std::max(v, 0.0) * px_[i].albedo[k];
      }
    }
    return out;
  }

 private:
  int w_, h_;
  const ImageFrame& f_;
  ImageParams p_;
  std::vector<Pixel> px_;
};

}  // namespace

std::vector<double> image_reference(int width, int height, const ImageFrame& frame, const ImageParams& params) {
  return Image(width, height, frame, params).run();
}

}  // namespace dn::test
