// Texel bindings (shaders/include/pass.glsl, access `texel`): a kernel reads
// a buffer through a uniform texel buffer view that DescriptorPool makes.
// bench_gather_texel sums each pixel's clamped 5x5 neighbourhood of vec4;
// the expectation is the same sum on the host. Rewriting the set to another
// buffer must make new views (the old ones are destroyed with the rewrite).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "dn/shaders/shaders.hpp"
#include "gpu/error.hpp"
#include "gpu_test_env.hpp"
#include "kernel_runner.hpp"

namespace dn {
namespace {

constexpr uint32_t kW = 37, kH = 23;  // odd sizes: partial workgroups and clamped borders

std::vector<float> random_rgba(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(-2.0f, 8.0f);
  std::vector<float> v(size_t{kW} * kH * 4);
  for (auto& x : v) x = d(rng);
  return v;
}

std::vector<float> host_sums(const std::vector<float>& rgba) {
  std::vector<float> out(rgba.size(), 0.0f);
  for (int y = 0; y < int(kH); ++y)
    for (int x = 0; x < int(kW); ++x)
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int qx = std::clamp(x + dx, 0, int(kW) - 1), qy = std::clamp(y + dy, 0, int(kH) - 1);
          for (int c = 0; c < 4; ++c) out[(size_t(y) * kW + x) * 4 + c] += rgba[(size_t(qy) * kW + qx) * 4 + c];
        }
  return out;
}

class TexelBindingTest : public test::GpuTest {};

TEST_F(TexelBindingTest, ReadsTheBufferItViewsAndFollowsARewrite) {
  const auto a = random_rgba(1), b = random_rgba(2);
  auto source_a = test::upload(ctx(), a, "source_a");
  auto source_b = test::upload(ctx(), b, "source_b");
  auto result = test::output<float>(ctx(), a.size(), "result");
  gpu::KernelDesc desc = test::grid_kernel_desc("bench_gather_texel", shaders::get("bench_gather_texel"), 2, 8);
  desc.texel_formats = {VK_FORMAT_UNDEFINED, VK_FORMAT_R32G32B32A32_SFLOAT};
  auto kernel = ctx().kernels().get(desc);

  gpu::Buffer uniform(ctx(), 256, gpu::BufferKind::Constants, "unused_frame_constants");
  gpu::DescriptorPool pool(ctx(), 1, 2);
  const VkBuffer first[2] = {result->handle(), source_a->handle()};
  VkDescriptorSet set = pool.allocate(*kernel, uniform.handle(), first);
  auto run = [&](const std::vector<float>& expected, const char* what) {
    gpu::CommandStream stream(ctx());
    VkCommandBuffer cmd = stream.begin();
    source_a->record_upload(cmd, source_a->size());
    source_b->record_upload(cmd, source_b->size());
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
    kernel->record_dispatch(cmd, set, test::grid(kW, kH));
    result->record_readback(cmd, result->size(), VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    stream.submit_and_wait();
    const auto got = test::read<float>(*result);
    double worst = 0.0;
    for (size_t i = 0; i < got.size(); ++i)
      worst = std::max(worst, double(std::abs(got[i] - expected[i])) / (1.0 + std::abs(expected[i])));
    EXPECT_LT(worst, 1e-5) << what;
  };
  run(host_sums(a), "first buffer");
  const VkBuffer second[2] = {result->handle(), source_b->handle()};
  pool.write(set, *kernel, uniform.handle(), second);
  run(host_sums(b), "after the set was rewritten to the second buffer");
}

TEST_F(TexelBindingTest, AKernelWithTexelFormatsForTheWrongBindingCountIsRefused) {
  gpu::KernelDesc desc = test::grid_kernel_desc("bench_gather_texel", shaders::get("bench_gather_texel"), 2, 8);
  desc.texel_formats = {VK_FORMAT_R32G32B32A32_SFLOAT};
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error);
}

}  // namespace
}  // namespace dn
