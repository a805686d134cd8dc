// ꟻLIP (dn/image/flip.hpp): against the reference implementation's values on the
// committed crop (tests/fixtures/flip/README.md), a per-formula double-precision
// colour difference on uniform images, and the properties the papers state.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/flip.hpp"

namespace {

using namespace dn::image;

struct Image {
  int w = 0, h = 0;
  std::vector<float> rgb;
};

// Binary PPM (P6, maxval 255) as values / 255.
Image read_ppm(const std::string& name) {
  const std::string path = std::string(DN_FLIP_FIXTURES) + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + path);
  Image im;
  int maxval = 0;
  if (std::fscanf(f, "P6 %d %d %d", &im.w, &im.h, &maxval) != 3 || maxval != 255) throw std::runtime_error(path);
  std::fgetc(f);
  std::vector<unsigned char> bytes(size_t(im.w) * size_t(im.h) * 3);
  const size_t got = std::fread(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  if (got != bytes.size()) throw std::runtime_error(path + ": short");
  for (unsigned char b : bytes) im.rgb.push_back(float(b) / 255.0f);
  return im;
}

double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// The fixture README's HDR pair: decoded and scaled by 2^(floor(8x/w) - 2) in eight column bands.
Image hdr_of(const Image& ldr) {
  Image out = ldr;
  for (int y = 0; y < ldr.h; ++y)
    for (int x = 0; x < ldr.w; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * size_t(ldr.w) + size_t(x)) * 3 + size_t(c);
        out.rgb[i] = float(srgb_decode(ldr.rgb[i]) * std::ldexp(1.0, 8 * x / ldr.w - 2));
      }
  return out;
}

double half_mean(const FlipResult& r, int w, int h, bool left) {
  double s = 0;
  for (int y = 0; y < h; ++y)
    for (int x = left ? 0 : w / 2; x < (left ? w / 2 : w); ++x) s += r.map[size_t(y) * size_t(w) + size_t(x)];
  return s / (double(w / 2) * h);
}

Image random_image(int w, int h, unsigned seed, float scale = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, scale);
  Image im{w, h, std::vector<float>(size_t(w) * size_t(h) * 3)};
  for (auto& v : im.rgb) v = u(rng);
  return im;
}

Image uniform_image(int w, int h, float r, float g, float b) {
  Image im{w, h, {}};
  for (int i = 0; i < w * h; ++i) im.rgb.insert(im.rgb.end(), {r, g, b});
  return im;
}

TEST(Flip, DefaultPixelsPerDegreeIsTheReferenceViewingCondition) {
  // 0.7 m from a 0.7 m wide 3840-pixel monitor: 3840 pixels per radian, times pi / 180 per degree.
  EXPECT_NEAR(kFlipDefaultPpd, 3840.0 * M_PI / 180.0, 1e-9);
  EXPECT_NEAR(kFlipDefaultPpd, 67.0206, 1e-4);
  EXPECT_NEAR(flip_pixels_per_degree(1.4, 1920.0, 0.7), 1.4 * 1920.0 / 0.7 * M_PI / 180.0, 1e-9);
}

TEST(Flip, LdrMatchesTheReferenceImplementationOnTheFixture) {
  const Image ref = read_ppm("reference.ppm"), test = read_ppm("test.ppm");
  ASSERT_EQ(ref.w, 128);
  ASSERT_EQ(ref.h, 96);
  const FlipResult r = flip_ldr(test.rgb.data(), ref.rgb.data(), ref.w, ref.h);
  ASSERT_EQ(r.map.size(), size_t(ref.w) * size_t(ref.h));
  EXPECT_NEAR(r.mean, 0.138418152, 2e-6);
  EXPECT_NEAR(half_mean(r, ref.w, ref.h, true), 0.158838400, 2e-6);   // the blurred half
  EXPECT_NEAR(half_mean(r, ref.w, ref.h, false), 0.117997904, 2e-6);  // the noisy half
  EXPECT_NEAR(r.map[10 * 128 + 10], 0.0913049, 2e-5);
  EXPECT_NEAR(r.map[50 * 128 + 100], 0.0909298, 2e-5);
}

TEST(Flip, HdrMatchesTheReferenceImplementationOnTheFixture) {
  const Image ref = hdr_of(read_ppm("reference.ppm")), test = hdr_of(read_ppm("test.ppm"));
  const FlipExposures e = flip_hdr_exposures(ref.rgb.data(), size_t(ref.w) * size_t(ref.h));
  EXPECT_NEAR(e.start, -3.903786, 2e-5);
  EXPECT_NEAR(e.stop, 3.156815, 2e-5);
  EXPECT_EQ(e.count, 8);  // ceil(stop - start)
  const FlipResult r = flip_hdr(test.rgb.data(), ref.rgb.data(), ref.w, ref.h);
  EXPECT_NEAR(r.mean, 0.241737121, 2e-6);
  EXPECT_NEAR(half_mean(r, ref.w, ref.h, true), 0.232435108, 2e-6);
  EXPECT_NEAR(half_mean(r, ref.w, ref.h, false), 0.251039133, 2e-6);
  EXPECT_NEAR(r.map[10 * 128 + 10], 0.1075963, 2e-5);
  EXPECT_NEAR(r.map[50 * 128 + 100], 0.1106609, 2e-5);
}

TEST(Flip, IdenticalImagesGiveZero) {
  const Image a = random_image(40, 30, 1);
  for (const FlipResult& r : {flip_ldr(a.rgb.data(), a.rgb.data(), a.w, a.h),
                              flip_hdr(a.rgb.data(), a.rgb.data(), a.w, a.h)}) {
    EXPECT_EQ(r.mean, 0.0);
    for (float v : r.map) ASSERT_EQ(v, 0.0f);
  }
}

TEST(Flip, EmptyImageHasMeanZero) {
  const FlipResult r = flip_ldr(nullptr, nullptr, 0, 0);
  EXPECT_TRUE(r.map.empty());
  EXPECT_EQ(r.mean, 0.0);
}

// Per-formula, in double, with the textbook sRGB matrix and D65 white (not the
// implementation's exact fractions): uniform images have no features and the
// normalised filters leave their colour as it is, so FLIP is the remapped HyAB.
struct Lab {
  double L, a, b;
};
Lab hunt_lab(double r, double g, double b) {
  const double X = 0.4124 * r + 0.3576 * g + 0.1805 * b, Y = 0.2126 * r + 0.7152 * g + 0.0722 * b,
               Z = 0.0193 * r + 0.1192 * g + 0.9505 * b;
  auto f = [](double t) { return t > std::pow(6.0 / 29.0, 3) ? std::cbrt(t) : t / (3 * std::pow(6.0 / 29.0, 2)) + 4.0 / 29.0; };
  const double fx = f(X / 0.95047), fy = f(Y), fz = f(Z / 1.08883);
  const double L = 116 * fy - 16;
  return {L, 0.01 * L * 500 * (fx - fy), 0.01 * L * 200 * (fy - fz)};
}
double hyab(Lab p, Lab q) { return std::fabs(p.L - q.L) + std::hypot(p.a - q.a, p.b - q.b); }
double expected_uniform_flip(const double a[3], const double b[3]) {
  const double cmax = std::pow(hyab(hunt_lab(0, 1, 0), hunt_lab(0, 0, 1)), 0.7), pc = 0.4 * cmax;
  const double d = std::pow(hyab(hunt_lab(a[0], a[1], a[2]), hunt_lab(b[0], b[1], b[2])), 0.7);
  return d < pc ? d * 0.95 / pc : 0.95 + (d - pc) / (cmax - pc) * 0.05;
}

TEST(Flip, UniformImagesGiveThePerFormulaColourDifference) {
  const double pairs[][2][3] = {{{0, 0, 0}, {1, 1, 1}},        {{0.2, 0.2, 0.2}, {0.25, 0.2, 0.2}},
                                {{0.5, 0.1, 0.1}, {0.1, 0.5, 0.1}}, {{0.05, 0.05, 0.3}, {0.05, 0.05, 0.32}},
                                {{0, 1, 0}, {0, 0, 1}},        {{0.8, 0.6, 0.4}, {0.7, 0.65, 0.4}}};
  for (const auto& p : pairs) {
    const Image a = uniform_image(24, 16, float(p[0][0]), float(p[0][1]), float(p[0][2]));
    const Image b = uniform_image(24, 16, float(p[1][0]), float(p[1][1]), float(p[1][2]));
    const FlipResult r = flip_ldr_linear(a.rgb.data(), b.rgb.data(), a.w, a.h);
    const double want = expected_uniform_flip(p[0], p[1]);
    EXPECT_NEAR(r.mean, want, 2e-3) << p[0][0] << "," << p[0][1] << "," << p[0][2];
    for (float v : r.map) ASSERT_NEAR(v, want, 2e-3);
  }
  // Green against blue is the largest difference the metric knows.
  const Image g = uniform_image(8, 8, 0, 1, 0), b = uniform_image(8, 8, 0, 0, 1);
  EXPECT_NEAR(flip_ldr_linear(g.rgb.data(), b.rgb.data(), 8, 8).mean, 1.0, 1e-4);
}

TEST(Flip, SrgbInputIsDecodedFirst) {
  const Image enc = random_image(32, 24, 2), enc2 = random_image(32, 24, 3);
  Image lin = enc, lin2 = enc2;
  for (auto& v : lin.rgb) v = float(srgb_decode(v));
  for (auto& v : lin2.rgb) v = float(srgb_decode(v));
  EXPECT_NEAR(flip_ldr(enc.rgb.data(), enc2.rgb.data(), 32, 24).mean,
              flip_ldr_linear(lin.rgb.data(), lin2.rgb.data(), 32, 24).mean, 1e-6);
}

TEST(Flip, LdrIsSymmetricAndInRange) {
  const Image a = random_image(48, 32, 4), b = random_image(48, 32, 5);
  const FlipResult ab = flip_ldr(a.rgb.data(), b.rgb.data(), 48, 32), ba = flip_ldr(b.rgb.data(), a.rgb.data(), 48, 32);
  EXPECT_EQ(ab.map, ba.map);
  for (float v : ab.map) {
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, 1.0f);
  }
  // Out-of-range and NaN inputs are clamped, never leak into the map.
  Image wild = a;
  wild.rgb[0] = NAN, wild.rgb[1] = -3.0f, wild.rgb[2] = 40.0f;
  for (float v : flip_ldr(wild.rgb.data(), b.rgb.data(), 48, 32).map) {
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, 1.0f);
  }
}

TEST(Flip, GrowsWithTheDifference) {
  const Image ref = read_ppm("reference.ppm");
  double previous = 0.0;
  for (float k : {0.01f, 0.03f, 0.06f, 0.1f, 0.2f}) {
    Image test = ref;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (auto& v : test.rgb) v = std::clamp(v + k * u(rng), 0.0f, 1.0f);
    const double ldr = flip_ldr(test.rgb.data(), ref.rgb.data(), ref.w, ref.h).mean;
    EXPECT_GT(ldr, previous) << "noise amplitude " << k;
    previous = ldr;
  }
  // HDR: the same for a growing gain error on linear radiance.
  const Image href = hdr_of(ref);
  previous = 0.0;
  for (float gain : {1.02f, 1.1f, 1.3f, 2.0f}) {
    Image test = href;
    for (auto& v : test.rgb) v *= gain;
    const double hdr = flip_hdr(test.rgb.data(), href.rgb.data(), ref.w, ref.h).mean;
    EXPECT_GT(hdr, previous) << "gain " << gain;
    previous = hdr;
  }
}

TEST(Flip, AcesCurveAndExposureRange) {
  // The tone curve at a few points, by the formula in double.
  for (double x : {0.01, 0.18, 1.0, 3.0, 100.0}) {
    const double want = (0.36 * 2.51 * x * x + 0.6 * 0.03 * x) / (0.36 * 2.43 * x * x + 0.6 * 0.59 * x + 0.14);
    EXPECT_NEAR(flip_aces(float(x)), want, 1e-6 * std::max(1.0, want)) << x;
  }
  EXPECT_EQ(flip_aces(-1.0f), 0.0f);
  EXPECT_EQ(flip_aces(NAN), 0.0f);
  // x85: where the curve reaches 0.85, found by bisection here.
  double lo = 0, hi = 100;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (lo + hi);
    (flip_aces(float(m)) < 0.85f ? lo : hi) = m;
  }
  // A reference of two luminances: max 4, median 0.3 (more than half the pixels).
  Image ref = uniform_image(10, 10, 0.3f, 0.3f, 0.3f);
  for (int i = 0; i < 30; ++i) ref.rgb[size_t(3 * i)] = ref.rgb[size_t(3 * i + 1)] = ref.rgb[size_t(3 * i + 2)] = 4.0f;
  const FlipExposures e = flip_hdr_exposures(ref.rgb.data(), 100);
  EXPECT_NEAR(e.start, std::log2(lo / 4.0), 1e-4);
  EXPECT_NEAR(e.stop, std::log2(lo / 0.3), 1e-4);
  EXPECT_EQ(e.count, 4);  // ceil(log2(4 / 0.3)) = ceil(3.74)
  // A constant reference gives one exposure, evaluated twice.
  const Image flat = uniform_image(4, 4, 0.5f, 0.5f, 0.5f);
  const FlipExposures ef = flip_hdr_exposures(flat.rgb.data(), 16);
  EXPECT_EQ(ef.start, ef.stop);
  EXPECT_EQ(ef.count, 2);
  // Nothing lit: exposure 0, and a median of zero falls back to the smallest lit luminance.
  const Image black = uniform_image(4, 4, 0, 0, 0);
  const FlipExposures eb = flip_hdr_exposures(black.rgb.data(), 16);
  EXPECT_EQ(eb.start, 0.0f);
  EXPECT_EQ(eb.stop, 0.0f);
  Image sparse = black;
  sparse.rgb[0] = sparse.rgb[1] = sparse.rgb[2] = 1.0f;
  sparse.rgb[3] = sparse.rgb[4] = sparse.rgb[5] = 0.125f;
  const FlipExposures es = flip_hdr_exposures(sparse.rgb.data(), 16);
  EXPECT_NEAR(es.stop - es.start, 3.0, 1e-5);
}

TEST(Flip, HdrIsTheMaximumOverItsExposures) {
  const Image ref = hdr_of(read_ppm("reference.ppm")), test = hdr_of(read_ppm("test.ppm"));
  const size_t n = size_t(ref.w) * size_t(ref.h);
  const FlipExposures e = flip_hdr_exposures(ref.rgb.data(), n);
  const FlipResult hdr = flip_hdr(test.rgb.data(), ref.rgb.data(), ref.w, ref.h, e);
  const float step = (e.stop - e.start) / float(e.count - 1);
  std::vector<float> most(n, 0.0f);
  for (int k = 0; k < e.count; ++k) {
    // LDR-ꟻLIP of the tone-mapped pair at this exposure, as the paper builds it.
    const float m = std::exp2(e.start + float(k) * step);
    Image a = test, b = ref;
    for (auto& v : a.rgb) v = std::clamp(flip_aces(v * m), 0.0f, 1.0f);
    for (auto& v : b.rgb) v = std::clamp(flip_aces(v * m), 0.0f, 1.0f);
    const FlipResult ldr = flip_ldr_linear(a.rgb.data(), b.rgb.data(), ref.w, ref.h);
    for (size_t i = 0; i < n; ++i) {
      ASSERT_GE(hdr.map[i], ldr.map[i]) << "exposure " << k << " pixel " << i;
      most[i] = std::max(most[i], ldr.map[i]);
    }
  }
  EXPECT_EQ(hdr.map, most);
  // One exposure given twice is that exposure's LDR-ꟻLIP.
  Image a = test, b = ref;
  for (auto& v : a.rgb) v = std::clamp(flip_aces(v), 0.0f, 1.0f);
  for (auto& v : b.rgb) v = std::clamp(flip_aces(v), 0.0f, 1.0f);
  EXPECT_EQ(flip_hdr(test.rgb.data(), ref.rgb.data(), ref.w, ref.h, FlipExposures{0.0f, 0.0f, 2}).map,
            flip_ldr_linear(a.rgb.data(), b.rgb.data(), ref.w, ref.h).map);
}

TEST(Flip, TonemappedLdrIsLdrOfTheToneMappedImages) {
  const Image ref = hdr_of(read_ppm("reference.ppm")), test = hdr_of(read_ppm("test.ppm"));
  Image a = test, b = ref;
  for (auto& v : a.rgb) v = tonemap(v * 0.5f, Tonemap::Reinhard);
  for (auto& v : b.rgb) v = tonemap(v * 0.5f, Tonemap::Reinhard);
  EXPECT_EQ(flip_ldr_tonemapped(test.rgb.data(), ref.rgb.data(), ref.w, ref.h, Tonemap::Reinhard, 0.5f).map,
            flip_ldr_linear(a.rgb.data(), b.rgb.data(), ref.w, ref.h).map);
}

}  // namespace
