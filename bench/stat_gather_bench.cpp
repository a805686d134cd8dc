// stat's disc gather with plain loads against a shared-memory tile (the
// server keeps what measures faster), on the device the server would choose (--device to pick
// another). Both run server/pipelines/stat/bench_stat_gather.comp (the membership test and
// base weight of stat_filter, stat_gather.glsl) in 8x8 workgroups over the
// same fp32 data: a smooth field seen through 16 samples per pixel with a
// hard edge, so that about as many taps fail the test as on rendered frames.
// The tile holds all five per-pixel vectors (80 B per texel), so it serves
// radius <= 6 in lavapipe's 32 KiB ((8 + 12)^2 x 80 = 32000 B); radius 20
// would need (8 + 40)^2 x 80 = 184 KB, so only plain loads run there.
// Prints one markdown row per size and radius: median device ms of --reps
// (10) dispatches each, and the largest difference between the two outputs.
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernel_bench.hpp"
#include "dn/shaders/shaders.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "pipelines/stat/student_t.hpp"

namespace {

constexpr uint32_t kBlock = 8;
constexpr uint32_t kApron = 6;  // the tile's apron (the largest radius it serves)
constexpr int kSamples = 16;    // the statistics' n
constexpr int kBuffers = 7;     // result, theta, variance, raw, albedo, normal, t_squared


// Per-pixel vec4 planes as stat_prepare leaves them: theta (Box-Cox mean of a
// pixel whose true value is a smooth field, halved right of a vertical edge,
// plus the noise of its mean), its variance of the mean, the raw mean, albedo
// in blocks and a normal that turns slowly.
struct Planes {
  std::vector<float> theta, variance, raw, albedo, normal;
};

Planes make_planes(uint32_t w, uint32_t h) {
  Planes p;
  const size_t n = size_t{w} * h * 4;
  for (auto* v : {&p.theta, &p.variance, &p.raw, &p.albedo, &p.normal}) v->assign(n, 0.0f);
  std::mt19937 rng(w * 131 + h);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = (size_t{y} * w + x) * 4;
      const float truth = (0.6f + 0.3f * std::sin(0.02f * x) * std::cos(0.03f * y)) * (x < w / 2 ? 1.0f : 0.5f);
      for (int c = 0; c < 3; ++c) {
        const float y_mean = 2.0f * std::sqrt(truth) - 2.0f, sd = 0.5f;  // Box-Cox units
        p.variance[i + c] = sd * sd / kSamples;
        p.theta[i + c] = y_mean + noise(rng) * sd / std::sqrt(float(kSamples));
        p.raw[i + c] = (p.theta[i + c] + 2.0f) * (p.theta[i + c] + 2.0f) / 4.0f;
        p.albedo[i + c] = 0.3f + 0.1f * float(((x / 16) + (y / 16) + c) % 4);
      }
      p.theta[i + 3] = kSamples;
      p.normal[i] = 0.1f * std::sin(0.01f * x);
      p.normal[i + 2] = 1.0f;
    }
  return p;
}

std::vector<float> read_floats(const dn::gpu::Buffer& b) {
  std::vector<float> out(b.size() / 4);
  b.read({reinterpret_cast<uint8_t*>(out.data()), b.size()});
  return out;
}

void run(dn::gpu::Context& ctx, uint32_t w, uint32_t h, int radius, int reps) {
  const Planes planes = make_planes(w, h);
  const uint64_t bytes = uint64_t{w} * h * 16;
  std::vector<dn::gpu::Buffer> buffers;
  buffers.emplace_back(ctx, bytes, dn::gpu::BufferKind::StorageDownload, "result");
  for (const auto* v : {&planes.theta, &planes.variance, &planes.raw, &planes.albedo, &planes.normal}) {
    buffers.emplace_back(ctx, bytes, dn::gpu::BufferKind::StorageUpload, "plane");
    buffers.back().write({reinterpret_cast<const uint8_t*>(v->data()), bytes});
  }
  std::vector<float> t2 = dn::pipelines::student_t_table(0.005, 1024);
  for (float& t : t2) t = t * t;
  buffers.emplace_back(ctx, t2.size() * 4, dn::gpu::BufferKind::StorageUpload, "t_squared");
  buffers.back().write({reinterpret_cast<const uint8_t*>(t2.data()), t2.size() * 4});
  dn::gpu::Buffer uniform(ctx, 256, dn::gpu::BufferKind::Constants, "unused");

  dn::gpu::GridPush grid;
  grid.size[0] = grid.source[0] = w;
  grid.size[1] = grid.source[1] = h;
  const float sigmas[3] = {radius == 6 ? 3.0f : 10.0f, 0.02f, 0.1f};  // paper 003's pairs (R 6, sigma 3; R 20, sigma 10)
  grid.args[0] = static_cast<uint32_t>(radius);
  for (int k = 0; k < 3; ++k) grid.args[1 + k] = std::bit_cast<uint32_t>(-0.5f / (sigmas[k] * sigmas[k]));

  auto time_variant = [&](bool tiled, std::vector<float>& out) {
    dn::gpu::KernelDesc desc;
    desc.name = tiled ? "bench_stat_gather_tiled" : "bench_stat_gather";
    desc.spirv = dn::shaders::get("bench_stat_gather");
    desc.storage_buffers = kBuffers;
    desc.spec_constants = {{1, tiled ? 1u : 0u}, {2, kApron}};
    desc.local_size_x = desc.local_size_y = kBlock;
    desc.push_constant_bytes = sizeof(dn::gpu::GridPush);
    auto kernel = ctx.kernels().get(desc);
    dn::gpu::DescriptorPool pool(ctx, 1, kBuffers);
    std::vector<VkBuffer> storage;
    for (const auto& b : buffers) storage.push_back(b.handle());
    VkDescriptorSet set = pool.allocate(*kernel, uniform.handle(), storage);
    const double ms = dn::bench::time_dispatches(
        ctx, buffers[0], reps, [&](VkCommandBuffer cmd) { kernel->record_dispatch(cmd, set, grid); },
        [&](VkCommandBuffer cmd) {
          for (size_t k = 1; k < buffers.size(); ++k) buffers[k].record_upload(cmd, buffers[k].size());
          dn::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
        });
    out = read_floats(buffers[0]);
    return ms;
  };
  std::vector<float> plain_out, tiled_out;
  const double plain_ms = time_variant(false, plain_out);
  // Members per pixel: the weight sum counts them only with weights, so report the mean weight sum.
  double weight = 0.0;
  for (size_t i = 3; i < plain_out.size(); i += 4) weight += plain_out[i];
  weight /= double(w) * h;
  if (radius > static_cast<int>(kApron)) {
    std::printf("| %ux%u | %d | %.1f | – (tile too large) | – | %.2f |\n", w, h, radius, plain_ms, weight);
    return;
  }
  const double tiled_ms = time_variant(true, tiled_out);
  double max_diff = 0.0;
  for (size_t i = 0; i < plain_out.size(); ++i) max_diff = std::max(max_diff, double(std::abs(plain_out[i] - tiled_out[i])));
  std::printf("| %ux%u | %d | %.1f | %.1f | %.3g | %.2f |\n", w, h, radius, plain_ms, tiled_ms, max_diff, weight);
}

}  // namespace

int main(int argc, char** argv) {
  dn::bench::KernelBenchOptions options;
  options.reps = 10;
  std::vector<int> radii;
  try {
    for (int i = 1; i < argc; ++i) {
      if (dn::bench::parse_kernel_bench_option(argc, argv, i, options)) continue;
      if (std::string(argv[i]) == "--radius" && i + 1 < argc) {
        radii.push_back(std::max(1, std::atoi(argv[++i])));
        continue;
      }
      std::fprintf(stderr, "usage: %s [--device SEL] [--size WxH]... [--radius R]... [--reps N]\n", argv[0]);
      return 2;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stat_gather_bench: %s\n", e.what());
    return 2;
  }
  if (options.sizes.empty()) options.sizes = {{640, 360}, {1280, 720}};
  if (radii.empty()) radii = {6, 20};
  return dn::bench::run_on_device("stat_gather_bench", options, [&](dn::gpu::Context& ctx) {
    std::printf("device: %s; median device ms of %d dispatches of stat's gather, 8x8 workgroups\n\n",
                ctx.name().c_str(), options.reps);
    std::printf("| size | radius | plain loads ms | shared tile ms | max diff | mean weight sum |\n");
    std::printf("| --- | --- | --- | --- | --- | --- |\n");
    for (auto [w, h] : options.sizes)
      for (int r : radii) run(ctx, w, h, r, options.reps);
  });
}
