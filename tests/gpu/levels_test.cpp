// Reduced-resolution grids: gpu::level_size and friends against the closed
// form ceil(n / factor^level), and levels.glsl through the pyramid_probe
// kernel, which builds a packed pyramid (mean of the valid pixels of each
// factor x factor block, a validity mask so no-data pixels never contribute)
// checked against a CPU reference at sizes that are and are not divisible.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "dn/shaders/shaders.hpp"
#include "gpu/levels.hpp"
#include "gpu_test_env.hpp"
#include "kernel_runner.hpp"

namespace dn {
namespace {

using Vec4 = std::array<float, 4>;
using gpu::Extent;

TEST(Levels, SizesAreCeilOfTheFactorPower) {
  for (uint32_t w : {1u, 2u, 3u, 8u, 9u, 10u, 37u, 243u, 244u, 1920u, 3840u})
    for (uint32_t h : {1u, 23u, 1080u})
      for (uint32_t f : {2u, 3u})
        for (uint32_t l = 0; l < 9; ++l) {
          const double p = std::pow(double(f), double(l));
          const Extent want{static_cast<uint32_t>(std::ceil(w / p)), static_cast<uint32_t>(std::ceil(h / p))};
          EXPECT_EQ(gpu::level_size(w, h, f, l), want) << w << "x" << h << " factor " << f << " level " << l;
        }
  EXPECT_EQ(gpu::level_size(37, 23, 2, 1), (Extent{19, 12}));  // half resolution
  EXPECT_EQ(gpu::level_size(37, 23, 3, 1), (Extent{13, 8}));   // third resolution
}

TEST(Levels, PyramidsRunDownToOnePixel) {
  EXPECT_EQ(gpu::level_count(37, 23, 3), 5u);  // 37x23, 13x8, 5x3, 2x1, 1x1
  EXPECT_EQ(gpu::level_count(243, 1, 3), 6u);  // 243, 81, 27, 9, 3, 1
  EXPECT_EQ(gpu::level_count(244, 1, 3), 7u);  // 244, 82, 28, 10, 4, 2, 1
  EXPECT_EQ(gpu::level_count(1, 1, 3), 1u);
  EXPECT_EQ(gpu::level_count(0, 5, 3), 0u);
  EXPECT_EQ(gpu::level_count(1920, 1080, 2), 12u);  // 1080 -> 540 ... 2 -> 1: 12 levels
  EXPECT_EQ(gpu::level_offset(37, 23, 3, 0), 0u);
  EXPECT_EQ(gpu::level_offset(37, 23, 3, 2), 37u * 23 + 13 * 8);
  EXPECT_EQ(gpu::pyramid_pixels(37, 23, 3), 37u * 23 + 13 * 8 + 5 * 3 + 2 * 1 + 1);
  // A 3x3 pyramid costs about 1/8 of the base level on top of it.
  const double extra = double(gpu::pyramid_pixels(1920, 1080, 3)) / (1920.0 * 1080.0) - 1.0;
  EXPECT_NEAR(extra, 1.0 / 8.0, 0.01);
}

struct Pyramid {
  std::vector<Vec4> values;
  std::vector<uint32_t> valid;
};

// The CPU reference, level by level from the definition.
Pyramid reference_pyramid(const Pyramid& base, uint32_t w, uint32_t h, uint32_t f) {
  Pyramid out = base;
  const uint32_t levels = gpu::level_count(w, h, f);
  for (uint32_t l = 1; l < levels; ++l) {
    const Extent fine = gpu::level_size(w, h, f, l - 1), coarse = gpu::level_size(w, h, f, l);
    const size_t fo = gpu::level_offset(w, h, f, l - 1);
    for (uint32_t y = 0; y < coarse.height; ++y)
      for (uint32_t x = 0; x < coarse.width; ++x) {
        double sum[4] = {};
        int n = 0;
        for (uint32_t fy = y * f; fy < std::min((y + 1) * f, fine.height); ++fy)
          for (uint32_t fx = x * f; fx < std::min((x + 1) * f, fine.width); ++fx) {
            const size_t i = fo + size_t{fy} * fine.width + fx;
            if (!out.valid[i]) continue;
            for (int k = 0; k < 4; ++k) sum[k] += out.values[i][k];
            ++n;
          }
        Vec4 v{};
        for (int k = 0; k < 4; ++k) v[k] = n ? static_cast<float>(sum[k] / n) : 0.0f;
        out.values.push_back(v);
        out.valid.push_back(n ? 1u : 0u);
      }
  }
  return out;
}

// Level 0: random values, ~30% no-data pixels holding NaN (any contribution
// would show), and a 7x7 hole so that whole coarse blocks are empty.
Pyramid base_level(uint32_t w, uint32_t h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(-1.0f, 4.0f);
  Pyramid p;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const bool hole = x >= 2 && x < 9 && y >= 2 && y < 9;
      const bool valid = !hole && rng() % 10 >= 3;
      Vec4 v;
      for (auto& c : v) c = valid ? dist(rng) : std::numeric_limits<float>::quiet_NaN();
      p.values.push_back(v);
      p.valid.push_back(valid ? 1u : 0u);
    }
  return p;
}

class PyramidTest : public test::GpuTest {
 protected:
  Pyramid build(const Pyramid& base, uint32_t w, uint32_t h, uint32_t f) {
    const size_t total = gpu::pyramid_pixels(w, h, f);
    Pyramid padded = base;
    padded.values.resize(total, Vec4{});
    padded.valid.resize(total, 0u);
    // The pyramid is read and written on the device: upload, then copy into
    // the buffers the host reads back.
    auto values_in = test::upload(ctx(), padded.values, "values_in");
    auto valid_in = test::upload(ctx(), padded.valid, "valid_in");
    auto values = test::output<Vec4>(ctx(), total, "values");
    auto valid = test::output<uint32_t>(ctx(), total, "valid");
    std::vector<gpu::GridPush> dispatches;
    for (uint32_t l = 1; l < gpu::level_count(w, h, f); ++l) {
      const Extent fine = gpu::level_size(w, h, f, l - 1), coarse = gpu::level_size(w, h, f, l);
      gpu::GridPush g;
      g.size[0] = coarse.width;
      g.size[1] = coarse.height;
      g.source[0] = fine.width;
      g.source[1] = fine.height;
      g.args[0] = l;
      g.args[1] = f;
      g.args[2] = w;
      g.args[3] = h;
      dispatches.push_back(g);
    }
    auto kernel = ctx().kernels().get(test::grid_kernel_desc("pyramid_probe", shaders::get("pyramid_probe"), 2, 8));
    test::run_grid_kernel(ctx(), *kernel, {values.get(), valid.get()}, dispatches, {values_in.get(), valid_in.get()},
                          {values.get(), valid.get()}, [&](VkCommandBuffer cmd) {
                            gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                                VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
                            const VkBufferCopy a{0, 0, values->size()}, b{0, 0, valid->size()};
                            vkCmdCopyBuffer(cmd, values_in->handle(), values->handle(), 1, &a);
                            vkCmdCopyBuffer(cmd, valid_in->handle(), valid->handle(), 1, &b);
                          });
    return {test::read<Vec4>(*values), test::read<uint32_t>(*valid)};
  }
};

TEST_F(PyramidTest, MatchesTheCpuReferenceAndNoDataNeverContributes) {
  struct Case {
    uint32_t w, h, f;
  };
  for (Case c : {Case{37, 23, 3}, Case{27, 9, 3}, Case{37, 23, 2}, Case{1, 1, 3}, Case{100, 1, 2},
                 Case{256, 144, 3}, Case{10, 10, 3}}) {
    SCOPED_TRACE(testing::Message() << c.w << "x" << c.h << " factor " << c.f);
    const Pyramid base = base_level(c.w, c.h, c.w * 7 + c.h + c.f);
    const Pyramid want = reference_pyramid(base, c.w, c.h, c.f);
    const Pyramid got = build(base, c.w, c.h, c.f);
    ASSERT_EQ(got.values.size(), want.values.size());
    const uint32_t levels = gpu::level_count(c.w, c.h, c.f);
    int failures = 0;
    uint32_t holes = 0;
    for (uint32_t l = 1; l < levels && failures < 5; ++l) {
      const Extent e = gpu::level_size(c.w, c.h, c.f, l);
      const size_t o = gpu::level_offset(c.w, c.h, c.f, l);
      for (size_t i = 0; i < e.pixels() && failures < 5; ++i) {
        const size_t j = o + i;
        holes += want.valid[j] == 0;
        if (got.valid[j] != want.valid[j]) {
          ADD_FAILURE() << "level " << l << " pixel (" << i % e.width << ", " << i / e.width << "): valid "
                        << got.valid[j] << ", want " << want.valid[j];
          ++failures;
          continue;
        }
        for (int k = 0; k < 4; ++k)
          if (!(std::abs(got.values[j][k] - want.values[j][k]) <= 1e-5f)) {
            ADD_FAILURE() << "level " << l << " pixel (" << i % e.width << ", " << i / e.width << ")[" << k
                          << "]: got " << got.values[j][k] << ", want " << want.values[j][k];
            ++failures;
            break;
          }
      }
    }
    if (c.w >= 27 && c.f == 3) {
      EXPECT_GT(holes, 0u) << "the 7x7 hole leaves a level-1 block without data";
    }
  }
}

}  // namespace
}  // namespace dn
