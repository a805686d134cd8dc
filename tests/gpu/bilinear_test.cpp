// bilinear.glsl through the bilinear_probe kernel: the fetch of a vec4
// buffer at continuous positions (pixel centres, edges, corners, beyond the
// grid, random) with taps masked invalid (holding NaN, which must never
// leak), against a double-precision CPU reference of the same definition.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "dn/shaders/shaders.hpp"
#include "gpu_test_env.hpp"
#include "kernel_runner.hpp"

namespace dn {
namespace {

using Vec2 = std::array<float, 2>;
using Vec4 = std::array<float, 4>;

struct Fetched {
  Vec4 value{};
  double weight = 0;
};

// Taps at the pixels around p - 0.5, weights (1 - t)/t per axis; taps
// outside, invalid or of weight 0 dropped, the rest renormalised.
Fetched reference_fetch(const std::vector<Vec4>& src, const std::vector<uint32_t>& valid, int w, int h, Vec2 p) {
  const double fx = double(p[0]) - 0.5, fy = double(p[1]) - 0.5;
  const double bx = std::floor(fx), by = std::floor(fy);
  const double tx = fx - bx, ty = fy - by;
  double sum[4] = {}, total = 0;
  for (int k = 0; k < 4; ++k) {
    const int dx = k & 1, dy = k >> 1;
    const double wt = (dx ? tx : 1 - tx) * (dy ? ty : 1 - ty);
    const double qx = bx + dx, qy = by + dy;
    if (!(wt > 0) || qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
    const size_t i = static_cast<size_t>(qy) * w + static_cast<size_t>(qx);
    if (!valid[i]) continue;
    for (int c = 0; c < 4; ++c) sum[c] += wt * src[i][c];
    total += wt;
  }
  Fetched f;
  f.weight = total;
  for (int c = 0; c < 4; ++c) f.value[c] = total > 0 ? static_cast<float>(sum[c] / total) : 0.0f;
  return f;
}

class BilinearTest : public test::GpuTest {
 protected:
  std::pair<std::vector<Vec4>, std::vector<float>> fetch(const std::vector<Vec4>& src, const std::vector<uint32_t>& valid,
                                                         uint32_t w, uint32_t h, const std::vector<Vec2>& positions,
                                                         uint32_t columns) {
    auto in = test::upload(ctx(), src, "source");
    auto mask = test::upload(ctx(), valid, "valid");
    auto pos = test::upload(ctx(), positions, "positions");
    auto result = test::output<Vec4>(ctx(), positions.size(), "result");
    auto weight = test::output<float>(ctx(), positions.size(), "weight");
    gpu::GridPush g = test::grid(columns, static_cast<uint32_t>(positions.size() / columns));
    g.source[0] = w;
    g.source[1] = h;
    auto kernel = ctx().kernels().get(test::grid_kernel_desc("bilinear_probe", shaders::get("bilinear_probe"), 5, 8));
    test::run_grid_kernel(ctx(), *kernel, {in.get(), mask.get(), pos.get(), result.get(), weight.get()}, {g},
                          {in.get(), mask.get(), pos.get()}, {result.get(), weight.get()});
    return {test::read<Vec4>(*result), test::read<float>(*weight)};
  }
};

TEST_F(BilinearTest, MatchesTheCpuReferenceAtEdgesAndInvalidTaps) {
  const uint32_t w = 13, h = 7;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> value(-2.0f, 5.0f);
  std::vector<Vec4> src(w * h);
  std::vector<uint32_t> valid(w * h);
  for (size_t i = 0; i < src.size(); ++i) {
    valid[i] = rng() % 4 != 0;
    for (auto& c : src[i]) c = valid[i] ? value(rng) : std::numeric_limits<float>::quiet_NaN();
  }
  for (uint32_t x = 4; x < 7; ++x)  // a 3x2 block of no data: positions inside it get nothing
    for (uint32_t y = 2; y < 4; ++y) valid[y * w + x] = 0, src[y * w + x][0] = std::numeric_limits<float>::quiet_NaN();

  // Exact positions (multiples of 1/8: pixel centres, edges, corners, half a
  // pixel and more beyond the grid), then random ones.
  std::vector<Vec2> positions;
  for (int y = -12; y <= int(h) * 8 + 12; y += 3)
    for (int x = -12; x <= int(w) * 8 + 12; x += 4) positions.push_back({x / 8.0f, y / 8.0f});
  std::uniform_real_distribution<float> px(-2.0f, w + 2.0f), py(-2.0f, h + 2.0f);
  while (positions.size() % 64 != 0 || positions.size() < 2048) positions.push_back({px(rng), py(rng)});
  positions.push_back({1e9f, -1e9f});  // far outside: no tap, and no overflow in the float -> int conversion
  positions.push_back({-1e30f, 3.5f});
  while (positions.size() % 64 != 0) positions.push_back({w / 2.0f, h / 2.0f});

  const auto [got, weight] = fetch(src, valid, w, h, positions, 64);
  int failures = 0, dropped = 0, empty = 0;
  for (size_t i = 0; i < positions.size() && failures < 5; ++i) {
    const Fetched want = reference_fetch(src, valid, w, h, positions[i]);
    empty += want.weight == 0;
    dropped += want.weight > 0 && want.weight < 0.999;
    bool ok = std::abs(weight[i] - want.weight) <= 1e-5;
    for (int c = 0; c < 4; ++c) ok = ok && std::abs(got[i][c] - want.value[c]) <= 2e-5f;
    if (!ok) {
      ADD_FAILURE() << "position (" << positions[i][0] << ", " << positions[i][1] << "): got (" << got[i][0] << ", "
                    << got[i][1] << ", " << got[i][2] << ", " << got[i][3] << ") weight " << weight[i] << ", want ("
                    << want.value[0] << ", " << want.value[1] << ", " << want.value[2] << ", " << want.value[3]
                    << ") weight " << want.weight;
      ++failures;
    }
  }
  // The cases the positions were chosen for did occur.
  EXPECT_GT(empty, 10);
  EXPECT_GT(dropped, 100);
}

TEST_F(BilinearTest, CentresReadTheirPixelAndBordersClamp) {
  const uint32_t w = 3, h = 2;
  std::vector<Vec4> src(w * h);
  for (uint32_t i = 0; i < w * h; ++i) src[i] = {float(i), float(10 * i), -float(i), 1.0f};
  // A valid NaN pixel: no position below gives it a weight above 0, and a
  // tap of weight 0 is never read (0 · NaN would leak).
  src[2].fill(std::numeric_limits<float>::quiet_NaN());
  const std::vector<uint32_t> valid(w * h, 1u);
  const std::vector<Vec2> positions = {
      {0.5f, 0.5f}, {2.5f, 1.5f},   // centres: that pixel, weight 1
      {0.0f, 0.0f}, {3.0f, 2.0f},   // outer corners: the corner pixel, weight 1/4
      {1.0f, 0.5f}, {1.5f, 1.0f},   // between two centres: the mean
      {-0.5f, 0.5f}, {3.5f, 2.5f},  // a pixel beyond the border: nothing
      {1.5f, 0.5f},                 // the centre next to the NaN pixel
  };
  const auto [got, weight] = fetch(src, valid, w, h, positions, static_cast<uint32_t>(positions.size()));
  EXPECT_EQ(got[0][0], 0.0f);
  EXPECT_EQ(weight[0], 1.0f);
  EXPECT_EQ(got[1][0], 5.0f);
  EXPECT_EQ(got[2][1], 0.0f);
  EXPECT_EQ(weight[2], 0.25f);
  EXPECT_EQ(got[3][1], 50.0f);
  EXPECT_EQ(weight[3], 0.25f);
  EXPECT_FLOAT_EQ(got[4][0], 0.5f);
  EXPECT_FLOAT_EQ(got[5][0], 2.5f);  // pixels 1 and 4
  EXPECT_EQ(weight[6], 0.0f);
  EXPECT_EQ(got[6][3], 0.0f);
  EXPECT_EQ(weight[7], 0.0f);
  EXPECT_EQ(got[8][0], 1.0f);
  EXPECT_EQ(weight[8], 1.0f);
}

}  // namespace
}  // namespace dn
