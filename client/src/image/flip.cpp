// ꟻLIP (LDR and HDR): definitions in dn/image/flip.hpp. Single precision like the
// reference implementation (NVlabs/flip), separable filters, clamped edges.
#include "dn/image/flip.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

namespace dn::image {

namespace {

constexpr float kPi = 3.14159265358979f;

// Constants of the HPG 2020 paper.
constexpr float kQc = 0.7f, kPc = 0.4f, kPt = 0.95f, kGw = 0.082f, kQf = 0.5f;

struct Vec3 {
  float x = 0, y = 0, z = 0;
};

// D65 white in XYZ and its reciprocal.
constexpr Vec3 kWhite{0.950428545f, 1.0f, 1.088900371f};
constexpr Vec3 kInvWhite{1.052156925f, 1.0f, 0.918357670f};

Vec3 linear_rgb_to_xyz(Vec3 c) {
  return {(10135552.0f / 24577794.0f) * c.x + (8788810.0f / 24577794.0f) * c.y + (4435075.0f / 24577794.0f) * c.z,
          (2613072.0f / 12288897.0f) * c.x + (8788810.0f / 12288897.0f) * c.y + (887015.0f / 12288897.0f) * c.z,
          (1425312.0f / 73733382.0f) * c.x + (8788810.0f / 73733382.0f) * c.y + (70074185.0f / 73733382.0f) * c.z};
}

Vec3 xyz_to_linear_rgb(Vec3 c) {
  return {3.241003275f * c.x - 1.537398934f * c.y - 0.498615861f * c.z,
          -0.969224334f * c.x + 1.875930071f * c.y + 0.041554224f * c.z,
          0.055639423f * c.x - 0.204011202f * c.y + 1.057148933f * c.z};
}

Vec3 xyz_to_ycxcz(Vec3 c) {
  const float x = c.x * kInvWhite.x, y = c.y * kInvWhite.y, z = c.z * kInvWhite.z;
  return {116.0f * y - 16.0f, 500.0f * (x - y), 200.0f * (y - z)};
}

Vec3 ycxcz_to_xyz(Vec3 c) {
  const float y = (c.x + 16.0f) / 116.0f;
  return {(y + c.y / 500.0f) * kWhite.x, y * kWhite.y, (y - c.z / 200.0f) * kWhite.z};
}

float lab_f(float t) {
  constexpr float d = 6.0f / 29.0f;
  return t > d * d * d ? std::cbrt(t) : t / (3.0f * d * d) + 4.0f / 29.0f;
}

Vec3 xyz_to_lab(Vec3 c) {
  const float fx = lab_f(c.x * kInvWhite.x), fy = lab_f(c.y * kInvWhite.y), fz = lab_f(c.z * kInvWhite.z);
  return {116.0f * fy - 16.0f, 500.0f * (fx - fy), 200.0f * (fy - fz)};
}

// Lab with the Hunt effect: chroma scales with lightness.
Vec3 hunt(Vec3 lab) { return {lab.x, 0.01f * lab.x * lab.y, 0.01f * lab.x * lab.z}; }

float hyab(Vec3 a, Vec3 b) {
  const float da = a.y - b.y, db = a.z - b.z;
  return std::fabs(a.x - b.x) + std::sqrt(da * da + db * db);
}

float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }

float clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }  // NaN -> 0

// The colour filter: a sum of Gaussians per channel, a * sqrt(pi / b) * exp(-pi^2 x^2 / b)
// per axis (x in degrees). Y and Cx are single Gaussians; Cz is two, each separable,
// so it is filtered as two separable passes that are added.
struct ColourFilters {
  int radius = 0;
  std::vector<float> y, cx, cz1, cz2;
};

ColourFilters colour_filters(float ppd) {
  constexpr float a1[3] = {1.0f, 1.0f, 34.1f}, b1[3] = {0.0047f, 0.0053f, 0.04f};
  constexpr float a2z = 13.5f, b2z = 0.025f;
  const float pi2 = kPi * kPi;
  // Radius from the widest Gaussian (b = 0.04): three standard deviations.
  const float bmax = std::max({b1[0], b1[1], b1[2], b2z});
  ColourFilters f;
  f.radius = int(std::ceil(3.0f * std::sqrt(bmax / (2.0f * pi2)) * ppd));
  const int n = 2 * f.radius + 1;
  f.y.resize(size_t(n)), f.cx.resize(size_t(n)), f.cz1.resize(size_t(n)), f.cz2.resize(size_t(n));
  float sy = 0, scx = 0, sz1 = 0, sz2 = 0;
  for (int i = 0; i < n; ++i) {
    const float d = float(i - f.radius) / ppd, d2 = d * d;
    const size_t k = size_t(i);
    f.y[k] = a1[0] * std::sqrt(kPi / b1[0]) * std::exp(-pi2 * d2 / b1[0]);
    f.cx[k] = a1[1] * std::sqrt(kPi / b1[1]) * std::exp(-pi2 * d2 / b1[1]);
    // Square roots of the amplitudes: the product of the two axes restores a * sqrt(pi / b).
    f.cz1[k] = std::sqrt(a1[2] * std::sqrt(kPi / b1[2])) * std::exp(-pi2 * d2 / b1[2]);
    f.cz2[k] = std::sqrt(a2z * std::sqrt(kPi / b2z)) * std::exp(-pi2 * d2 / b2z);
    sy += f.y[k], scx += f.cx[k], sz1 += f.cz1[k], sz2 += f.cz2[k];
  }
  // Each 2D filter sums to 1: the Cz filter's 2D sum is sz1^2 + sz2^2.
  const float nz = 1.0f / std::sqrt(sz1 * sz1 + sz2 * sz2);
  for (size_t k = 0; k < size_t(n); ++k) f.y[k] /= sy, f.cx[k] /= scx, f.cz1[k] *= nz, f.cz2[k] *= nz;
  return f;
}

// Gaussian, its first and second derivatives, for edge and point detection.
struct FeatureFilters {
  int radius = 0;
  std::vector<float> g, dg, ddg;
};

FeatureFilters feature_filters(float ppd) {
  const float sigma = 0.5f * kGw * ppd;
  FeatureFilters f;
  f.radius = int(std::ceil(3.0f * sigma));
  const int n = 2 * f.radius + 1;
  f.g.resize(size_t(n)), f.dg.resize(size_t(n)), f.ddg.resize(size_t(n));
  float gs = 0, dpos = 0, dneg = 0, ddpos = 0, ddneg = 0;
  for (int i = 0; i < n; ++i) {
    const float x = float(i - f.radius);
    const float g = std::exp(-(x * x) / (2.0f * sigma * sigma));
    const float dg = -x * g, ddg = (x * x / (sigma * sigma) - 1.0f) * g;
    const size_t k = size_t(i);
    f.g[k] = g, f.dg[k] = dg, f.ddg[k] = ddg;
    gs += g;
    (dg > 0 ? dpos : dneg) += std::fabs(dg);
    (ddg > 0 ? ddpos : ddneg) += std::fabs(ddg);
  }
  // Gaussian sums to 1; each derivative's positive weights to 1, its negative ones to -1.
  for (size_t k = 0; k < size_t(n); ++k) {
    f.g[k] /= gs;
    f.dg[k] /= f.dg[k] > 0 ? dpos : dneg;
    f.ddg[k] /= f.ddg[k] > 0 ? ddpos : ddneg;
  }
  return f;
}

// One image in YCxCz, planar.
struct Planes {
  std::vector<float> y, cx, cz;
};

Planes to_ycxcz(const float* linear_rgb, size_t n) {
  Planes p;
  p.y.resize(n), p.cx.resize(n), p.cz.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = xyz_to_ycxcz(linear_rgb_to_xyz(
        {clamp01(linear_rgb[3 * i]), clamp01(linear_rgb[3 * i + 1]), clamp01(linear_rgb[3 * i + 2])}));
    p.y[i] = c.x, p.cx[i] = c.y, p.cz[i] = c.z;
  }
  return p;
}

// Horizontal then vertical pass of one separable kernel, clamped edges.
std::vector<float> filter_x(const std::vector<float>& in, int w, int h, const std::vector<float>& k, int r) {
  std::vector<float> out(in.size());
  for (int y = 0; y < h; ++y) {
    const float* row = in.data() + size_t(y) * size_t(w);
    for (int x = 0; x < w; ++x) {
      float s = 0;
      for (int i = -r; i <= r; ++i) s += k[size_t(i + r)] * row[std::clamp(x + i, 0, w - 1)];
      out[size_t(y) * size_t(w) + size_t(x)] = s;
    }
  }
  return out;
}

std::vector<float> filter_y(const std::vector<float>& in, int w, int h, const std::vector<float>& k, int r) {
  std::vector<float> out(in.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float s = 0;
      for (int i = -r; i <= r; ++i) s += k[size_t(i + r)] * in[size_t(std::clamp(y + i, 0, h - 1)) * size_t(w) + size_t(x)];
      out[size_t(y) * size_t(w) + size_t(x)] = s;
    }
  return out;
}

std::vector<float> filter_2d(const std::vector<float>& in, int w, int h, const std::vector<float>& k, int r) {
  return filter_y(filter_x(in, w, h, k, r), w, h, k, r);
}

// The CSF-filtered image in Hunt-adjusted L*a*b*, per pixel.
std::vector<Vec3> filtered_lab(const Planes& p, int w, int h, const ColourFilters& f) {
  const int r = f.radius;
  const auto y = filter_2d(p.y, w, h, f.y, r);
  const auto cx = filter_2d(p.cx, w, h, f.cx, r);
  const auto cz1 = filter_2d(p.cz, w, h, f.cz1, r);
  const auto cz2 = filter_2d(p.cz, w, h, f.cz2, r);
  std::vector<Vec3> out(y.size());
  for (size_t i = 0; i < out.size(); ++i) {
    Vec3 rgb = xyz_to_linear_rgb(ycxcz_to_xyz({y[i], cx[i], cz1[i] + cz2[i]}));
    rgb = {clamp01(rgb.x), clamp01(rgb.y), clamp01(rgb.z)};  // filtering can leave the gamut
    out[i] = hunt(xyz_to_lab(linear_rgb_to_xyz(rgb)));
  }
  return out;
}

// Edge and point strengths of the normalised achromatic channel.
void features(const Planes& p, int w, int h, const FeatureFilters& f, std::vector<float>& edge,
              std::vector<float>& point) {
  const int r = f.radius;
  std::vector<float> yn(p.y.size());
  for (size_t i = 0; i < yn.size(); ++i) yn[i] = (p.y[i] + 16.0f) / 116.0f;
  const auto gx = filter_x(yn, w, h, f.g, r), dx = filter_x(yn, w, h, f.dg, r), ddx = filter_x(yn, w, h, f.ddg, r);
  const auto ex = filter_y(dx, w, h, f.g, r), ey = filter_y(gx, w, h, f.dg, r);
  const auto px = filter_y(ddx, w, h, f.g, r), py = filter_y(gx, w, h, f.ddg, r);
  edge.resize(yn.size()), point.resize(yn.size());
  for (size_t i = 0; i < yn.size(); ++i) {
    edge[i] = std::sqrt(ex[i] * ex[i] + ey[i] * ey[i]);
    point[i] = std::sqrt(px[i] * px[i] + py[i] * py[i]);
  }
}

// The largest colour difference: HyAB of pure green and pure blue, raised to qc.
float max_colour_difference() {
  const Vec3 g = hunt(xyz_to_lab(linear_rgb_to_xyz({0, 1, 0})));
  const Vec3 b = hunt(xyz_to_lab(linear_rgb_to_xyz({0, 0, 1})));
  return std::pow(hyab(g, b), kQc);
}

// LDR-ꟻLIP of two display-linear images (clamped to [0,1] on the way in).
std::vector<float> ldr_map(const float* rgb, const float* ref_rgb, int w, int h, float ppd) {
  const size_t n = size_t(w) * size_t(h);
  if (n == 0) return {};
  const Planes t = to_ycxcz(rgb, n), r = to_ycxcz(ref_rgb, n);
  const ColourFilters cf = colour_filters(ppd);
  const auto lt = filtered_lab(t, w, h, cf), lr = filtered_lab(r, w, h, cf);
  const FeatureFilters ff = feature_filters(ppd);
  std::vector<float> et, pt, er, pr;
  features(t, w, h, ff, et, pt);
  features(r, w, h, ff, er, pr);

  const float cmax = max_colour_difference(), pccmax = kPc * cmax;
  const float inv_sqrt2 = 1.0f / std::sqrt(2.0f);
  std::vector<float> map(n);
  for (size_t i = 0; i < n; ++i) {
    float de = std::pow(hyab(lr[i], lt[i]), kQc);
    // Differences up to pc * cmax take [0, pt]; the rest (pt, 1].
    de = de < pccmax ? de * (kPt / pccmax) : kPt + (de - pccmax) / (cmax - pccmax) * (1.0f - kPt);
    const float df = std::pow(inv_sqrt2 * std::max(std::fabs(er[i] - et[i]), std::fabs(pr[i] - pt[i])), kQf);
    map[i] = std::pow(de, 1.0f - df);
  }
  return map;
}

FlipResult with_mean(std::vector<float> map) {
  FlipResult r;
  double sum = 0.0;
  for (float v : map) sum += v;
  r.mean = map.empty() ? 0.0 : sum / double(map.size());
  r.map = std::move(map);
  return r;
}

float finite_or_zero(float v) { return std::isfinite(v) ? v : 0.0f; }

}  // namespace

double flip_pixels_per_degree(double distance_m, double resolution_x, double monitor_width_m) {
  return distance_m * (resolution_x / monitor_width_m) * (3.14159265358979323846 / 180.0);
}

FlipResult flip_ldr_linear(const float* rgb, const float* ref_rgb, int width, int height, double ppd) {
  return with_mean(ldr_map(rgb, ref_rgb, width, height, float(ppd)));
}

FlipResult flip_ldr(const float* srgb, const float* ref_srgb, int width, int height, double ppd) {
  const size_t c = size_t(width) * size_t(height) * 3;
  std::vector<float> a(c), b(c);
  for (size_t i = 0; i < c; ++i) a[i] = srgb_to_linear(clamp01(srgb[i])), b[i] = srgb_to_linear(clamp01(ref_srgb[i]));
  return flip_ldr_linear(a.data(), b.data(), width, height, ppd);
}

FlipResult flip_ldr_tonemapped(const float* rgb, const float* ref_rgb, int width, int height, Tonemap t,
                               float exposure, double ppd) {
  // tonemap() already gives display-linear values; no sRGB round trip needed.
  const size_t c = size_t(width) * size_t(height) * 3;
  std::vector<float> a(c), b(c);
  for (size_t i = 0; i < c; ++i) a[i] = tonemap(rgb[i] * exposure, t), b[i] = tonemap(ref_rgb[i] * exposure, t);
  return flip_ldr_linear(a.data(), b.data(), width, height, ppd);
}

float flip_aces(float x) {
  if (!(x > 0.0f)) return 0.0f;
  constexpr float a = 0.6f * 0.6f * 2.51f, b = 0.6f * 0.03f, c = 0.6f * 0.6f * 2.43f, d = 0.6f * 0.59f, e = 0.14f;
  if (std::isinf(x)) return a / c;
  // Divided through by x^2 above 1, so huge values do not overflow to inf/inf.
  return x <= 1.0f ? (x * (a * x + b)) / (x * (c * x + d) + e) : (a + b / x) / (c + d / x + e / (x * x));
}

FlipExposures flip_hdr_exposures(const float* ref_rgb, size_t pixels) {
  // Where flip_aces reaches 0.85: the larger root of (a - t c) x^2 + (b - t d) x - t e = 0.
  constexpr float t = 0.85f;
  constexpr float a = 0.6f * 0.6f * 2.51f - t * 0.6f * 0.6f * 2.43f, b = 0.6f * 0.03f - t * 0.6f * 0.59f,
                  c = -t * 0.14f;
  const float d1 = -0.5f * b / a;
  const float x85 = d1 + std::sqrt(d1 * d1 - c / a);

  std::vector<float> lum(pixels);
  float ymax = -std::numeric_limits<float>::infinity(), ymin_pos = std::numeric_limits<float>::infinity();
  for (size_t i = 0; i < pixels; ++i) {
    const float y = finite_or_zero(linear_luminance(ref_rgb[3 * i], ref_rgb[3 * i + 1], ref_rgb[3 * i + 2]));
    lum[i] = y;
    ymax = std::max(ymax, y);
    if (y > 0.0f) ymin_pos = std::min(ymin_pos, y);
  }
  FlipExposures e;
  if (!(ymax > 0.0f)) return e;  // nothing lit: one exposure pair at 0
  std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(pixels / 2), lum.end());
  float ymedian = lum[pixels / 2];
  if (!(ymedian > 0.0f)) ymedian = ymin_pos;
  e.start = std::log2(x85 / ymax);
  e.stop = std::log2(x85 / ymedian);
  e.count = std::max(2, int(std::ceil(e.stop - e.start)));
  return e;
}

FlipResult flip_hdr(const float* rgb, const float* ref_rgb, int width, int height, double ppd) {
  return flip_hdr(rgb, ref_rgb, width, height, flip_hdr_exposures(ref_rgb, size_t(width) * size_t(height)), ppd);
}

FlipResult flip_hdr(const float* rgb, const float* ref_rgb, int width, int height, const FlipExposures& exposures,
                    double ppd) {
  const size_t n = size_t(width) * size_t(height), c = n * 3;
  const int count = std::max(exposures.count, 2);
  const float step = (exposures.stop - exposures.start) / float(count - 1);
  // The exposures are independent: spread over the cores (the maximum does not depend on the order).
  const int workers = std::clamp(int(std::thread::hardware_concurrency()), 1, count);
  std::vector<std::vector<float>> best(size_t(workers), std::vector<float>(n, 0.0f));
  auto run = [&](int worker) {
    std::vector<float> a(c), b(c);
    for (int k = worker; k < count; k += workers) {
      const float m = std::exp2(exposures.start + float(k) * step);
      for (size_t i = 0; i < c; ++i) a[i] = clamp01(flip_aces(rgb[i] * m)), b[i] = clamp01(flip_aces(ref_rgb[i] * m));
      const auto map = ldr_map(a.data(), b.data(), width, height, float(ppd));
      auto& mine = best[size_t(worker)];
      for (size_t i = 0; i < n; ++i) mine[i] = std::max(mine[i], map[i]);
    }
  };
  std::vector<std::thread> threads;
  for (int w = 1; w < workers; ++w) threads.emplace_back(run, w);
  run(0);
  for (auto& t : threads) t.join();
  for (size_t w = 1; w < best.size(); ++w)
    for (size_t i = 0; i < n; ++i) best[0][i] = std::max(best[0][i], best[w][i]);
  return with_mean(std::move(best[0]));
}

}  // namespace dn::image
