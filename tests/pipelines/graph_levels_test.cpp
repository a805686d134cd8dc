// Buffers at reduced resolution and 2-D grid passes inside a pass graph: a
// packed pyramid scratch (factor 2 and 3, sizes that do not divide) built by
// grid passes at each level's resolution, then read back at full resolution,
// against a double-precision CPU reference. Shaders: level_probe and
// pyramid_probe (test kernels, shaders/*.comp).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "frames.hpp"
#include "gpu/levels.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

class GraphLevelsTest : public test::GpuTest {};

struct Case {
  uint32_t width, height, factor, level;
};

// CPU reference: level 0 = the radiance (no-data where red < 0); each coarser
// pixel the mean of its valid children; output = the ancestor at `level`.
std::vector<double> reference(const std::vector<float>& radiance, const Case& c) {
  struct Level {
    gpu::Extent size;
    std::vector<double> rgb;
    std::vector<bool> valid;
  };
  std::vector<Level> levels(1);
  levels[0].size = {c.width, c.height};
  for (size_t i = 0; i < size_t{c.width} * c.height; ++i) {
    levels[0].valid.push_back(radiance[3 * i] >= 0.0f);
    for (int k = 0; k < 3; ++k) levels[0].rgb.push_back(radiance[3 * i + k]);
  }
  for (uint32_t l = 1; l <= c.level; ++l) {
    const Level& fine = levels.back();
    Level coarse;
    coarse.size = {(fine.size.width + c.factor - 1) / c.factor, (fine.size.height + c.factor - 1) / c.factor};
    for (uint32_t y = 0; y < coarse.size.height; ++y)
      for (uint32_t x = 0; x < coarse.size.width; ++x) {
        double sum[3] = {0, 0, 0};
        int n = 0;
        for (uint32_t fy = y * c.factor; fy < std::min((y + 1) * c.factor, fine.size.height); ++fy)
          for (uint32_t fx = x * c.factor; fx < std::min((x + 1) * c.factor, fine.size.width); ++fx) {
            const size_t i = size_t{fy} * fine.size.width + fx;
            if (!fine.valid[i]) continue;
            for (int k = 0; k < 3; ++k) sum[k] += fine.rgb[3 * i + k];
            ++n;
          }
        coarse.valid.push_back(n > 0);
        for (int k = 0; k < 3; ++k) coarse.rgb.push_back(n > 0 ? sum[k] / n : 0.0);
      }
    levels.push_back(std::move(coarse));
  }
  const Level& top = levels.back();
  std::vector<double> out;
  for (uint32_t y = 0; y < c.height; ++y)
    for (uint32_t x = 0; x < c.width; ++x) {
      uint32_t qx = x, qy = y;
      for (uint32_t l = 0; l < c.level; ++l) qx /= c.factor, qy /= c.factor;
      const size_t a = size_t{qy} * top.size.width + qx;
      for (int k = 0; k < 3; ++k) out.push_back(top.valid[a] ? top.rgb[3 * a + k] : 0.0);
    }
  return out;
}

TEST_F(GraphLevelsTest, PyramidAtReducedResolutionsMatchesCpuReference) {
  for (const Case c : {Case{37, 23, 3, 2}, Case{40, 24, 2, 3}, Case{5, 40, 2, 5}}) {
    SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height) + " factor " + std::to_string(c.factor));
    const auto config = test::make_config("passthrough", c.width, c.height, {{ChannelId::Radiance, Format::F32}});
    auto g = std::make_shared<pipelines::GraphSpec>();
    g->width = c.width;
    g->height = c.height;
    g->add_input(config, ChannelId::Radiance, "radiance");
    g->add_output(config);
    const uint64_t elements = gpu::pyramid_pixels(c.width, c.height, c.factor);
    g->add_scratch_elements("values", elements, 16);
    g->add_scratch_elements("valid", elements, 4);
    const gpu::Extent full = g->level(c.factor, 0);
    g->add_pass("fill", "level_probe")
        .bind("radiance", "radiance").bind("values", "values").bind("valid", "valid").bind("result", "output")
        .mode("fill")
        .over_grid(full, full);
    for (uint32_t l = 1; l <= c.level; ++l)
      g->add_pass("pull_" + std::to_string(l), "pyramid_probe")
          .bind("values", "values").bind("valid", "valid")
          .over_grid(g->level(c.factor, l), g->level(c.factor, l - 1))
          .arg("level", l).arg("factor", c.factor).arg("width0", c.width).arg("height0", c.height);
    g->add_pass("read", "level_probe")
        .bind("radiance", "radiance").bind("values", "values").bind("valid", "valid").bind("result", "output")
        .mode("read")
        .over_grid(full, full)
        .arg("level", c.level).arg("factor", c.factor).arg("width0", c.width).arg("height0", c.height);
    g->check();
    // The coarsest level is smaller than the session: a reduced-resolution grid.
    EXPECT_LT(g->level(c.factor, c.level).pixels(), full.pixels());

    std::mt19937 rng(c.width * 131 + c.factor);
    std::uniform_real_distribution<float> value(0.0f, 4.0f);
    std::vector<float> radiance(3 * full.pixels());
    for (size_t i = 0; i < full.pixels(); ++i) {
      const bool hole = (i % 7 == 3) || (i / c.width >= 2 && i / c.width < 6 && i % c.width < 5);  // and a block
      for (int k = 0; k < 3; ++k) radiance[3 * i + k] = hole ? -1.0f : value(rng);
    }
    test::HostFrame frame;
    frame.add(ChannelId::Radiance, Format::F32, radiance);
    pipelines::GraphPipeline pipe(ctx(), config, g);
    std::vector<uint8_t> output;
    std::vector<pipelines::PassTiming> timings;
    test::process(pipe, frame.view(), true, output, timings);
    const std::vector<float> got = test::decode_output(output, Format::F32);
    const std::vector<double> want = reference(radiance, c);
    ASSERT_EQ(got.size(), want.size());
    double worst = 0;
    for (size_t i = 0; i < got.size(); ++i) worst = std::max(worst, std::abs(got[i] - want[i]));
    EXPECT_LT(worst, 1e-5) << "largest absolute difference";
    EXPECT_EQ(timings.size(), g->passes.size() + 2);  // every grid pass is timed like any other
  }
}

}  // namespace
}  // namespace dn
