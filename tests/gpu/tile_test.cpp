// 2-D kernels (KernelDesc::local_size_x/y, push constants, grid2d.glsl) and
// shared-memory tiles (tile.glsl) through the tile_probe kernel: a disc
// gather of radius up to the apron, over a clamped tile and over the taps
// inside the grid, against a double-precision CPU reference at odd sizes,
// every border included.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <random>

#include "dn/shaders/shaders.hpp"
#include "gpu/error.hpp"
#include "gpu_test_env.hpp"
#include "kernel_runner.hpp"

namespace dn {
namespace {

using Vec4 = std::array<float, 4>;

struct Gathered {
  std::vector<Vec4> clamped;  // Gaussian over the disc, taps clamped to the border
  std::vector<Vec4> inside;   // box mean over the disc's taps inside the grid
};

// The CPU reference: straight from the definition, no tile.
Gathered reference(const std::vector<Vec4>& src, int w, int h, int r, double sigma) {
  Gathered out{std::vector<Vec4>(src.size()), std::vector<Vec4>(src.size())};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double g[4] = {}, b[4] = {}, gw = 0, bn = 0;
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          if (dx * dx + dy * dy > r * r) continue;
          const int qx = x + dx, qy = y + dy;
          const double wt = std::exp(-(dx * dx + dy * dy) / (2.0 * sigma * sigma));
          const Vec4& c = src[std::clamp(qy, 0, h - 1) * w + std::clamp(qx, 0, w - 1)];
          for (int k = 0; k < 4; ++k) g[k] += wt * c[k];
          gw += wt;
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
          for (int k = 0; k < 4; ++k) b[k] += src[qy * w + qx][k];
          bn += 1;
        }
      for (int k = 0; k < 4; ++k) {
        out.clamped[y * w + x][k] = static_cast<float>(g[k] / gw);
        out.inside[y * w + x][k] = static_cast<float>(b[k] / bn);
      }
    }
  return out;
}

class TileTest : public test::GpuTest {
 protected:
  std::shared_ptr<const gpu::Kernel> kernel(uint32_t block, uint32_t apron) {
    return ctx().kernels().get(test::grid_kernel_desc("tile_probe", shaders::get("tile_probe"), 3, block, {{1, apron}}));
  }

  Gathered run(const gpu::Kernel& k, const std::vector<Vec4>& src, uint32_t w, uint32_t h, uint32_t r, float sigma) {
    auto in = test::upload(ctx(), src, "source");
    auto clamped = test::output<Vec4>(ctx(), src.size(), "clamped");
    auto inside = test::output<Vec4>(ctx(), src.size(), "inside");
    gpu::GridPush g = test::grid(w, h);
    g.args[0] = r;
    g.args[1] = std::bit_cast<uint32_t>(sigma);
    test::run_grid_kernel(ctx(), k, {in.get(), clamped.get(), inside.get()}, {g}, {in.get()},
                          {clamped.get(), inside.get()});
    return {test::read<Vec4>(*clamped), test::read<Vec4>(*inside)};
  }
};

std::vector<Vec4> random_image(uint32_t w, uint32_t h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(0.0f, 1.0f);
  std::vector<Vec4> out(size_t{w} * h);
  for (auto& p : out)
    for (auto& c : p) c = dist(rng);
  return out;
}

void expect_near(const std::vector<Vec4>& got, const std::vector<Vec4>& want, uint32_t w, const char* what) {
  ASSERT_EQ(got.size(), want.size());
  int failures = 0;
  for (size_t i = 0; i < got.size() && failures < 5; ++i)
    for (int k = 0; k < 4; ++k)
      if (!(std::abs(got[i][k] - want[i][k]) <= 2e-5f)) {
        ADD_FAILURE() << what << " at (" << i % w << ", " << i / w << ")[" << k << "]: got " << got[i][k]
                      << ", want " << want[i][k];
        ++failures;
        break;
      }
}

TEST_F(TileTest, DiscGatherMatchesTheCpuReferenceAtOddSizes) {
  struct Size {
    uint32_t w, h;
  };
  for (uint32_t block : {8u, 16u}) {
    for (uint32_t apron : {3u, 8u}) {
      auto k = kernel(block, apron);
      for (Size s : {Size{37, 23}, Size{16, 16}, Size{1, 1}, Size{5, 40}, Size{256, 144}}) {
        const auto src = random_image(s.w, s.h, s.w * 1000 + s.h);
        for (uint32_t r : {0u, 1u, 3u, 8u}) {
          if (r > apron) continue;
          for (float sigma : {0.7f, 3.0f}) {
            SCOPED_TRACE(testing::Message() << "block " << block << ", apron " << apron << ", " << s.w << "x" << s.h
                                            << ", R " << r << ", sigma " << sigma);
            const Gathered got = run(*k, src, s.w, s.h, r, sigma);
            const Gathered want = reference(src, static_cast<int>(s.w), static_cast<int>(s.h), static_cast<int>(r), sigma);
            expect_near(got.clamped, want.clamped, s.w, "clamped");
            expect_near(got.inside, want.inside, s.w, "inside");
          }
        }
      }
    }
  }
}

// The reference itself must tell a clamped tap from a dropped one, or the
// test above could not catch a tile that mixes them up.
TEST(TileReference, ClampedAndInsideDifferAtTheBorderOnly) {
  const auto src = random_image(9, 7, 1);
  const Gathered g = reference(src, 9, 7, 2, 1e6);  // sigma huge: the Gaussian is a box
  EXPECT_NEAR(g.clamped[4 * 9 + 4][0], g.inside[4 * 9 + 4][0], 1e-6);  // interior: same taps
  EXPECT_GT(std::abs(g.clamped[0][0] - g.inside[0][0]), 1e-4);          // corner: clamped taps repeat (0, 0)
}

TEST_F(TileTest, KernelDescShapesAndPushConstants) {
  auto k8 = kernel(8, 8);
  auto k16 = kernel(16, 8);
  EXPECT_NE(k8.get(), k16.get()) << "the cache keys on the workgroup shape";
  EXPECT_EQ(k8.get(), kernel(8, 8).get());
  EXPECT_EQ(k8->local_size(), (std::array<uint32_t, 2>{8, 8}));
  EXPECT_EQ(k8->push_constant_bytes(), sizeof(gpu::GridPush));
  EXPECT_EQ(k8->groups(37, 23), (std::array<uint32_t, 2>{5, 3}));
  EXPECT_EQ(k16->groups(37, 23), (std::array<uint32_t, 2>{3, 2}));
  EXPECT_EQ(k16->groups(16, 16), (std::array<uint32_t, 2>{1, 1}));

  auto desc = test::grid_kernel_desc("tile_probe", shaders::get("tile_probe"), 3, 8, {{1, 8}});
  desc.local_size_y = 4;  // not square
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error);
  desc = test::grid_kernel_desc("tile_probe", shaders::get("tile_probe"), 3, 8, {{0, 8}, {1, 8}});
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error) << "constant 0 twice";
  desc = test::grid_kernel_desc("tile_probe", shaders::get("tile_probe"), 3, 8, {{1, 8}});
  desc.push_constant_bytes = gpu::kMaxPushConstantBytes + 4;
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error);
  desc.push_constant_bytes = 6;
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error);
  desc = test::grid_kernel_desc("tile_probe", shaders::get("tile_probe"), 3, 0, {{1, 8}});
  desc.local_size_y = 8;
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error) << "local_size_y without local_size_x";
}

// 1-D kernels keep working as before: constant 0 from spec_constants, no
// shape, no push constants.
TEST_F(TileTest, OneDimensionalKernelsAreUnchanged) {
  gpu::KernelDesc desc;
  desc.name = "plane_probe";
  desc.spirv = shaders::get("plane_probe");
  desc.storage_buffers = 2;
  desc.spec_constants = {{0, 64}, {1, 1}};
  auto k = ctx().kernels().get(desc);
  EXPECT_EQ(k->local_size(), (std::array<uint32_t, 2>{0, 0}));
  EXPECT_EQ(k->push_constant_bytes(), 0u);
  EXPECT_THROW(k->groups(10, 10), gpu::Error);
}

}  // namespace
}  // namespace dn
