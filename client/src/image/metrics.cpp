#include "dn/image/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dn::image {

Tonemap parse_tonemap(std::string_view name) {
  if (name == "aces") return Tonemap::Aces;
  if (name == "reinhard") return Tonemap::Reinhard;
  if (name == "clamp") return Tonemap::Clamp;
  throw std::invalid_argument("unknown tone map '" + std::string(name) + "' (expected aces, reinhard or clamp)");
}

const char* to_string(Tonemap t) {
  switch (t) {
    case Tonemap::Aces: return "aces";
    case Tonemap::Reinhard: return "reinhard";
    case Tonemap::Clamp: return "clamp";
  }
  return "?";
}

float tonemap(float x, Tonemap t) {
  if (!(x > 0.0f)) return 0.0f;  // NaN, negatives, zero
  if (std::isinf(x)) return 1.0f;
  float y = 0.0f;
  switch (t) {
    case Tonemap::Aces: {
      // Krzysztof Narkowicz, "ACES Filmic Tone Mapping Curve" (2015).
      const float a = 2.51f, b = 0.03f, c = 2.43f, d = 0.59f, e = 0.14f;
      // Divided through by x^2 above 1, so huge values do not overflow to inf/inf.
      y = x <= 1.0f ? (x * (a * x + b)) / (x * (c * x + d) + e) : (a + b / x) / (c + d / x + e / (x * x));
      break;
    }
    case Tonemap::Reinhard: y = x / (1.0f + x); break;
    case Tonemap::Clamp: y = x; break;
  }
  return std::clamp(y, 0.0f, 1.0f);
}

float srgb_oetf(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

float linear_luminance(float r, float g, float b) { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }

std::vector<uint8_t> to_srgb8(const float* rgb, size_t pixels, Tonemap t, float exposure) {
  std::vector<uint8_t> out(pixels * 3);
  for (size_t i = 0; i < pixels * 3; ++i) {
    float v = srgb_oetf(tonemap(rgb[i] * exposure, t));
    out[i] = uint8_t(std::lround(v * 255.0f));
  }
  return out;
}

std::vector<float> display_luma(const float* rgb, size_t pixels, Tonemap t, float exposure) {
  std::vector<float> out(pixels);
  for (size_t i = 0; i < pixels; ++i) {
    const float r = srgb_oetf(tonemap(rgb[3 * i + 0] * exposure, t));
    const float g = srgb_oetf(tonemap(rgb[3 * i + 1] * exposure, t));
    const float b = srgb_oetf(tonemap(rgb[3 * i + 2] * exposure, t));
    out[i] = std::clamp(0.2126f * r + 0.7152f * g + 0.0722f * b, 0.0f, 1.0f);
  }
  return out;
}

double rmse(const float* a, const float* ref, size_t count) {
  if (count == 0) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const double d = double(a[i]) - double(ref[i]);
    sum += d * d;
  }
  return std::sqrt(sum / double(count));
}

double relative_mse(const float* a, const float* ref, size_t count, double eps) {
  if (count == 0) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const double r = ref[i];
    const double d = double(a[i]) - r;
    sum += d * d / (r * r + eps);
  }
  return sum / double(count);
}

double noise_corrected_mse(const float* a, const float* ref1, const float* ref2, size_t count) {
  if (count == 0) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < count; ++i) sum += (double(a[i]) - ref1[i]) * (double(a[i]) - ref2[i]);
  return sum / double(count);
}

double noise_corrected_relative_mse(const float* a, const float* ref1, const float* ref2, size_t count, double eps) {
  if (count == 0) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const double m = 0.5 * (double(ref1[i]) + ref2[i]);
    sum += (double(a[i]) - ref1[i]) * (double(a[i]) - ref2[i]) / (m * m + eps);
  }
  return sum / double(count);
}

double reference_noise_mse(const float* ref1, const float* ref2, size_t count) {
  if (count == 0) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const double d = double(ref1[i]) - ref2[i];
    sum += d * d;
  }
  return 0.5 * sum / double(count);
}

namespace {

// Separable Gaussian blur restricted to 'valid' output positions: output has
// (w - k + 1) x (h - k + 1) samples.
std::vector<double> blur_valid(const std::vector<double>& in, int w, int h, const std::vector<double>& k) {
  const int n = int(k.size());
  const int ow = w - n + 1, oh = h - n + 1;
  std::vector<double> tmp(size_t(ow) * size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < ow; ++x) {
      double s = 0.0;
      const double* row = in.data() + size_t(y) * size_t(w) + size_t(x);
      for (int i = 0; i < n; ++i) s += k[size_t(i)] * row[i];
      tmp[size_t(y) * size_t(ow) + size_t(x)] = s;
    }
  std::vector<double> out(size_t(ow) * size_t(oh));
  for (int y = 0; y < oh; ++y)
    for (int x = 0; x < ow; ++x) {
      double s = 0.0;
      for (int i = 0; i < n; ++i) s += k[size_t(i)] * tmp[size_t(y + i) * size_t(ow) + size_t(x)];
      out[size_t(y) * size_t(ow) + size_t(x)] = s;
    }
  return out;
}

std::vector<double> gaussian_kernel(int size, double sigma) {
  std::vector<double> k(static_cast<size_t>(size));
  double sum = 0.0;
  const double c = 0.5 * (size - 1);
  for (int i = 0; i < size; ++i) {
    const double d = i - c;
    k[size_t(i)] = std::exp(-d * d / (2.0 * sigma * sigma));
    sum += k[size_t(i)];
  }
  for (auto& v : k) v /= sum;
  return k;
}

}  // namespace

double ssim(const float* x, const float* y, int width, int height) {
  constexpr double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
  if (width <= 0 || height <= 0) return 1.0;
  const size_t n = size_t(width) * size_t(height);
  if (width < 11 || height < 11) {
    // One window over the whole (small) image, uniform weights.
    double mx = 0, my = 0;
    for (size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
    mx /= double(n), my /= double(n);
    double vx = 0, vy = 0, cxy = 0;
    for (size_t i = 0; i < n; ++i) {
      vx += (x[i] - mx) * (x[i] - mx);
      vy += (y[i] - my) * (y[i] - my);
      cxy += (x[i] - mx) * (y[i] - my);
    }
    vx /= double(n), vy /= double(n), cxy /= double(n);
    return ((2 * mx * my + C1) * (2 * cxy + C2)) / ((mx * mx + my * my + C1) * (vx + vy + C2));
  }
  const auto map = ssim_map(x, y, width, height);
  double sum = 0.0;
  for (double v : map) sum += v;
  return sum / double(map.size());
}

std::vector<double> ssim_map(const float* x, const float* y, int width, int height) {
  constexpr double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
  if (width < 11 || height < 11) return {};
  const size_t n = size_t(width) * size_t(height);
  const auto k = gaussian_kernel(11, 1.5);
  std::vector<double> X(n), Y(n), XX(n), YY(n), XY(n);
  for (size_t i = 0; i < n; ++i) {
    X[i] = x[i], Y[i] = y[i];
    XX[i] = X[i] * X[i], YY[i] = Y[i] * Y[i], XY[i] = X[i] * Y[i];
  }
  const auto mx = blur_valid(X, width, height, k), my = blur_valid(Y, width, height, k);
  const auto sxx = blur_valid(XX, width, height, k), syy = blur_valid(YY, width, height, k),
             sxy = blur_valid(XY, width, height, k);
  std::vector<double> map(mx.size());
  for (size_t i = 0; i < mx.size(); ++i) {
    const double vx = sxx[i] - mx[i] * mx[i], vy = syy[i] - my[i] * my[i], cxy = sxy[i] - mx[i] * my[i];
    map[i] = ((2 * mx[i] * my[i] + C1) * (2 * cxy + C2)) / ((mx[i] * mx[i] + my[i] * my[i] + C1) * (vx + vy + C2));
  }
  return map;
}

double ssim_tonemapped(const float* rgb, const float* ref_rgb, int width, int height, Tonemap t, float exposure) {
  const size_t n = size_t(width) * size_t(height);
  const auto a = display_luma(rgb, n, t, exposure);
  const auto b = display_luma(ref_rgb, n, t, exposure);
  return ssim(a.data(), b.data(), width, height);
}

double temporal_error(const float* rgb, const float* prev_rgb, size_t pixels) {
  if (pixels == 0) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < pixels; ++i) {
    const double a = linear_luminance(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
    const double b = linear_luminance(prev_rgb[3 * i], prev_rgb[3 * i + 1], prev_rgb[3 * i + 2]);
    sum += std::fabs(a - b);
  }
  return sum / double(pixels);
}

double temporal_error(const float* rgb, const float* prev_rgb, const uint8_t* mask, size_t pixels) {
  double sum = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < pixels; ++i) {
    if (!mask[i]) continue;
    const double a = linear_luminance(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
    const double b = linear_luminance(prev_rgb[3 * i], prev_rgb[3 * i + 1], prev_rgb[3 * i + 2]);
    sum += std::fabs(a - b);
    ++n;
  }
  return n ? sum / double(n) : std::nan("");
}

}  // namespace dn::image
