// Neighbourhood reads: a storage buffer against a uniform texel buffer.
//
// On lavapipe every data-dependent storage-buffer word is a per-lane scalar
// load with a bounds check, which is what the a-trous and variance passes
// cost (docs/results.md, "Interactive on two cores: what llvmpipe spends time
// on"). Texel fetches go through
// the sampler's gather instead. Every pixel of a WxH vec4 grid sums its 5x5
// neighbourhood (clamped): shaders/bench_gather_buffer.comp from the storage
// buffer, bench_gather_texel.comp through an RGBA32F uniform texel buffer
// view of the same buffer, 8x8 workgroups. Prints one markdown row per size
// (--size WxH, repeatable; default 640x360, 1280x720): the median device ms
// of --reps (30) timed dispatches of each, their ratio, and the largest
// difference between the two outputs (both must compute the same sums).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "dn/shaders/shaders.hpp"
#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "kernel_bench.hpp"

namespace {

constexpr uint32_t kBlock = 8;

dn::gpu::GridPush grid_of(uint32_t w, uint32_t h) {
  dn::gpu::GridPush g{};
  g.size[0] = g.source[0] = w;
  g.size[1] = g.source[1] = h;
  return g;
}

void run(dn::gpu::Context& ctx, uint32_t w, uint32_t h, int reps) {
  const std::vector<float> rgba = dn::bench::random_rgba(w, h);
  const uint64_t bytes = rgba.size() * 4;
  dn::gpu::Buffer source(ctx, bytes, dn::gpu::BufferKind::StorageUpload, "source");
  source.write({reinterpret_cast<const uint8_t*>(rgba.data()), bytes});
  auto upload = [&](VkCommandBuffer cmd) {
    source.record_upload(cmd, bytes);
    dn::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                            VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
  };

  dn::gpu::Buffer uniform(ctx, 256, dn::gpu::BufferKind::Constants, "unused");
  dn::gpu::DescriptorPool pool(ctx, 2, 4);
  // The same kernel twice: source a storage buffer, then a texel buffer.
  auto time_kernel = [&](const char* shader, VkFormat texel, std::vector<float>& out) {
    dn::gpu::Buffer result(ctx, bytes, dn::gpu::BufferKind::StorageDownload, "result");
    dn::gpu::KernelDesc desc;
    desc.name = shader;
    desc.spirv = dn::shaders::get(shader);
    desc.storage_buffers = 2;
    if (texel != VK_FORMAT_UNDEFINED) desc.texel_formats = {VK_FORMAT_UNDEFINED, texel};
    desc.local_size_x = desc.local_size_y = kBlock;
    desc.push_constant_bytes = sizeof(dn::gpu::GridPush);
    auto kernel = ctx.kernels().get(desc);
    const VkBuffer storage[2] = {result.handle(), source.handle()};
    VkDescriptorSet set = pool.allocate(*kernel, uniform.handle(), storage);
    const double ms = dn::bench::time_dispatches(
        ctx, result, reps, [&](VkCommandBuffer cmd) { kernel->record_dispatch(cmd, set, grid_of(w, h)); }, upload);
    out = dn::bench::read_floats(result);
    return ms;
  };
  std::vector<float> from_buffer, from_texels;
  const double buffer_ms = time_kernel("bench_gather_buffer", VK_FORMAT_UNDEFINED, from_buffer);
  const double texel_ms = time_kernel("bench_gather_texel", VK_FORMAT_R32G32B32A32_SFLOAT, from_texels);
  double max_diff = 0.0;
  for (size_t i = 0; i < from_buffer.size(); ++i)
    max_diff = std::max(max_diff, double(std::abs(from_texels[i] - from_buffer[i])));
  std::printf("| %ux%u | %.3f | %.3f | %.2f | %.2g |\n", w, h, buffer_ms, texel_ms, texel_ms / buffer_ms, max_diff);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  dn::bench::KernelBenchOptions options;
  options.reps = 30;
  if (!dn::bench::parse_kernel_bench_args(argc, argv, "gather_bench", options)) return 2;
  if (options.sizes.empty()) options.sizes = {{640, 360}, {1280, 720}};
  return dn::bench::run_on_device("gather_bench", options, [&](dn::gpu::Context& ctx) {
    std::printf("device: %s; median device ms of %d dispatches, a 5x5 vec4 neighbourhood per pixel\n\n",
                ctx.name().c_str(), options.reps);
    std::printf("| size | storage buffer | uniform texel buffer | texel / buffer | max diff |\n");
    std::printf("| --- | --- | --- | --- | --- |\n");
    for (auto [w, h] : options.sizes) run(ctx, w, h, options.reps);
  });
}
