#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "dn/image/metrics.hpp"

namespace {

using namespace dn::image;

TEST(Metrics, RmseOfKnownImages) {
  const std::vector<float> a = {0, 0, 0, 0}, b = {1, 1, 1, 1};
  EXPECT_DOUBLE_EQ(rmse(a.data(), b.data(), 4), 1.0);
  const std::vector<float> c = {1, 2, 3}, d = {1, 2, 5};
  EXPECT_DOUBLE_EQ(rmse(c.data(), d.data(), 3), std::sqrt(4.0 / 3.0));
  EXPECT_DOUBLE_EQ(rmse(c.data(), c.data(), 3), 0.0);
}

TEST(Metrics, RelativeMse) {
  const std::vector<float> a = {2, 0}, ref = {1, 0};
  // ((2-1)^2/(1+0.01) + 0) / 2
  EXPECT_NEAR(relative_mse(a.data(), ref.data(), 2), 0.5 / 1.01, 1e-12);
  EXPECT_NEAR(relative_mse(a.data(), ref.data(), 2, 1.0), 0.25, 1e-12);
}

TEST(Metrics, SsimIdentityIsOneAndDropsWithNoise) {
  const int w = 48, h = 40;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.2f, 0.8f);
  std::vector<float> x(size_t(w * h));
  for (int y = 0; y < h; ++y)
    for (int i = 0; i < w; ++i) x[size_t(y * w + i)] = 0.5f + 0.3f * std::sin(0.3f * float(i)) * std::cos(0.2f * float(y));
  EXPECT_NEAR(ssim(x.data(), x.data(), w, h), 1.0, 1e-12);

  std::normal_distribution<float> n(0.0f, 1.0f);
  double prev = 1.0;
  for (float sigma : {0.02f, 0.1f, 0.3f}) {
    std::vector<float> y = x;
    for (auto& v : y) v = std::clamp(v + sigma * n(rng), 0.0f, 1.0f);
    const double s = ssim(x.data(), y.data(), w, h);
    EXPECT_LT(s, prev) << "sigma " << sigma;
    EXPECT_GT(s, 0.0);
    prev = s;
  }
  EXPECT_LT(prev, 0.5);
}

TEST(Metrics, SsimOfConstantsMatchesFormula) {
  // For constant images every window has zero variance, so
  // SSIM = (2ab + C1) / (a^2 + b^2 + C1), C1 = 0.01^2 — in the Gaussian path
  // (>= 11x11) and in the small-image path alike.
  const double a = 0.2, b = 0.4, C1 = 1e-4;
  const double expect = (2 * a * b + C1) / (a * a + b * b + C1);
  for (int size : {16, 6}) {
    std::vector<float> x(size_t(size * size), float(a)), y(size_t(size * size), float(b));
    EXPECT_NEAR(ssim(x.data(), y.data(), size, size), expect, 1e-6) << size;
  }
}

TEST(Metrics, SsimTonemappedOnRgb) {
  const int w = 16, h = 16;
  std::vector<float> rgb(size_t(w * h * 3), 0.0f);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = float(i % 13) * 0.3f;
  EXPECT_NEAR(ssim_tonemapped(rgb.data(), rgb.data(), w, h), 1.0, 1e-12);
  std::vector<float> darker = rgb;
  for (auto& v : darker) v *= 0.5f;
  EXPECT_LT(ssim_tonemapped(darker.data(), rgb.data(), w, h), 0.99);
}

TEST(Metrics, ToneMapsAndOetf) {
  EXPECT_EQ(tonemap(0.0f, Tonemap::Aces), 0.0f);
  EXPECT_EQ(tonemap(std::nanf(""), Tonemap::Aces), 0.0f);
  EXPECT_EQ(tonemap(-2.0f, Tonemap::Reinhard), 0.0f);
  EXPECT_FLOAT_EQ(tonemap(1.0f, Tonemap::Reinhard), 0.5f);
  EXPECT_EQ(tonemap(1e30f, Tonemap::Aces), 1.0f);  // the curve tends to 2.51/2.43 > 1: clamped
  // ACES fit at 1: (2.51 + 0.03) / (2.43 + 0.59 + 0.14)
  EXPECT_NEAR(tonemap(1.0f, Tonemap::Aces), 2.54 / 3.16, 1e-6);
  float last = 0.0f;
  for (float x = 0.01f; x < 100.0f; x *= 1.5f) {
    const float y = tonemap(x, Tonemap::Aces);
    EXPECT_GE(y, last);
    last = y;
  }
  EXPECT_NEAR(srgb_oetf(0.5f), 0.735357, 1e-5);
  EXPECT_NEAR(srgb_oetf(0.002f), 0.02584, 1e-6);
  EXPECT_FLOAT_EQ(srgb_oetf(1.0f), 1.0f);
  EXPECT_EQ(parse_tonemap("reinhard"), Tonemap::Reinhard);
  EXPECT_THROW(parse_tonemap("filmic"), std::invalid_argument);
}

TEST(Metrics, NoiseCorrectedOfKnownImages) {
  const std::vector<float> a = {2, 1}, r1 = {1, 1}, r2 = {3, 0};
  // ((2-1)(2-3) + (1-1)(1-0)) / 2
  EXPECT_DOUBLE_EQ(noise_corrected_mse(a.data(), r1.data(), r2.data(), 2), -0.5);
  // (-1 / (2^2 + 0.01) + 0) / 2
  EXPECT_NEAR(noise_corrected_relative_mse(a.data(), r1.data(), r2.data(), 2), -0.5 / 4.01, 1e-12);
  // ((1-3)^2 + (1-0)^2) / 2 / 2
  EXPECT_DOUBLE_EQ(reference_noise_mse(r1.data(), r2.data(), 2), 1.25);
  // Identical references: the plain MSE, and no noise.
  EXPECT_DOUBLE_EQ(noise_corrected_mse(a.data(), r1.data(), r1.data(), 2), std::pow(rmse(a.data(), r1.data(), 2), 2));
  EXPECT_DOUBLE_EQ(reference_noise_mse(r1.data(), r1.data(), 2), 0.0);
  EXPECT_EQ(noise_corrected_mse(a.data(), r1.data(), r2.data(), 0), 0.0);
}

// Synthetic truth t, an estimate x = t + e (e fixed, its true MSE known) and
// two references r1 = t + n1, r2 = t + n2 with independent Gaussian noise of
// standard deviation s. Per component, (x - r1)(x - r2) has mean e^2 and
// variance 2 e^2 s^2 + s^4, so the mean over N components is within
// 5 sqrt((2 M s^2 + s^4) / N) of the true MSE M (5 standard errors; fixed seed);
// (r1 - r2)^2 / 2 has mean s^2 and variance 2 s^4.
TEST(Metrics, NoiseCorrectedMseConvergesToTheTrueMse) {
  constexpr size_t N = 300000;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> truth(0.2f, 2.0f);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  for (const double s : {0.05, 0.2, 0.5}) {
    std::vector<float> t(N), x(N), r1(N), r2(N);
    for (size_t i = 0; i < N; ++i) {
      t[i] = truth(rng);
      x[i] = t[i] + 0.05f * unit(rng) + 0.02f;  // noise and a bias
      r1[i] = t[i] + float(s) * unit(rng);
      r2[i] = t[i] + float(s) * unit(rng);
    }
    const double true_mse = std::pow(rmse(x.data(), t.data(), N), 2);
    const double nc = noise_corrected_mse(x.data(), r1.data(), r2.data(), N);
    const double tol = 5.0 * std::sqrt((2.0 * true_mse * s * s + s * s * s * s) / double(N));
    EXPECT_NEAR(nc, true_mse, tol) << "s " << s;
    // The plain MSE against one reference carries the reference's variance.
    const double plain = std::pow(rmse(x.data(), r1.data(), N), 2);
    const double plain_tol = 5.0 * std::sqrt((4.0 * true_mse * s * s + 2.0 * s * s * s * s) / double(N));
    EXPECT_NEAR(plain, true_mse + s * s, plain_tol) << "s " << s;
    EXPECT_GT(plain - true_mse, 10.0 * tol) << "s " << s;
    // The reference's own noise floor is its variance.
    EXPECT_NEAR(reference_noise_mse(r1.data(), r2.data(), N), s * s, 5.0 * s * s * std::sqrt(2.0 / double(N)))
        << "s " << s;
  }
}

TEST(Metrics, NoiseCorrectedMseOfThePerfectImageIsNearZero) {
  // x = truth: the estimate is zero-mean noise of standard error s^2 / sqrt(N),
  // either sign; the plain MSE is s^2.
  constexpr size_t N = 200000;
  const double s = 0.3;
  std::mt19937 rng(11);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> t(N, 1.0f), r1(N), r2(N);
  for (size_t i = 0; i < N; ++i) r1[i] = 1.0f + float(s) * unit(rng), r2[i] = 1.0f + float(s) * unit(rng);
  const double nc = noise_corrected_mse(t.data(), r1.data(), r2.data(), N);
  EXPECT_NEAR(nc, 0.0, 5.0 * s * s / std::sqrt(double(N)));
  EXPECT_NEAR(std::pow(rmse(t.data(), r1.data(), N), 2), s * s, 5.0 * s * s * std::sqrt(2.0 / double(N)));
}

TEST(Metrics, NoiseCorrectedRelativeMseRemovesMostOfTheNoiseBias) {
  // The relative form divides by the references' mean, which carries noise
  // correlated with the numerator: it is unbiased only to first order in s / t
  // (the next term is about 3 (e^2 s^2 / 2 + s^4 / 2) / t^4: 0.75 % here, the
  // standard error 0.3 %). With x and the references each 5 % off the truth it
  // is within 3 % of the true relative MSE, while the plain relative MSE
  // against r1 is twice it.
  constexpr size_t N = 300000;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> truth(1.0f, 4.0f);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> t(N), x(N), r1(N), r2(N);
  for (size_t i = 0; i < N; ++i) {
    t[i] = truth(rng);
    x[i] = t[i] * (1.0f + 0.05f * unit(rng));
    r1[i] = t[i] * (1.0f + 0.05f * unit(rng));
    r2[i] = t[i] * (1.0f + 0.05f * unit(rng));
  }
  const double truth_rel = relative_mse(x.data(), t.data(), N);
  const double nc_rel = noise_corrected_relative_mse(x.data(), r1.data(), r2.data(), N);
  EXPECT_NEAR(nc_rel, truth_rel, 0.03 * truth_rel);
  EXPECT_GT(relative_mse(x.data(), r1.data(), N), 1.8 * truth_rel);
}

TEST(Metrics, TemporalError) {
  const std::vector<float> a = {1, 1, 1, 0, 0, 0}, b = {0, 0, 0, 0, 0, 0};
  EXPECT_NEAR(temporal_error(a.data(), b.data(), 2), 0.5, 1e-6);
  // Over a mask: only the masked pixels count, and none gives NaN.
  const std::vector<float> c = {2, 2, 2, 0, 0, 0, 1, 1, 1}, d(9, 0.0f);
  const std::vector<uint8_t> first_last = {1, 0, 1}, none = {0, 0, 0};
  EXPECT_NEAR(temporal_error(c.data(), d.data(), first_last.data(), 3), 1.5, 1e-6);
  EXPECT_TRUE(std::isnan(temporal_error(c.data(), d.data(), none.data(), 3)));
}

}  // namespace
