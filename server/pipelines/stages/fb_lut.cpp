#include "pipelines/stages/fb_lut.hpp"

#include <chrono>

#include "dn/shaders/declaration.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "pipelines/frame_constants.hpp"  // kWorkgroupSize
#include "pipelines/pass.hpp"             // kernel_desc

namespace dn::pipelines {
namespace {

constexpr uint32_t kTexels = kFbLutSize * kFbLutSize;
constexpr uint64_t kTableBytes = uint64_t{kTexels} * 2 * sizeof(float);
static_assert(kTexels % kWorkgroupSize == 0, "one invocation per texel, whole workgroups");

}  // namespace

FbLut::FbLut(gpu::Context& ctx)
    : ctx_(ctx), table_(ctx, kTableBytes, gpu::BufferKind::Storage, "fb_lut") {
  PassSpec pass("fb_lut", "fb_lut");
  pass.set("SAMPLES", kFbLutSamples);
  auto kernel = ctx.kernels().get(kernel_desc(pass.declaration(), pass.specialization(kWorkgroupSize)));

  // Binding 0 of every kernel layout is the constants buffer; fb_lut.comp reads none.
  gpu::Buffer constants(ctx, 16, gpu::BufferKind::Constants, "fb_lut:constants");
  const uint32_t zeros[4] = {};
  constants.write({reinterpret_cast<const uint8_t*>(zeros), sizeof zeros});
  gpu::DescriptorPool pool(ctx, 1, 1);
  const VkBuffer storage[] = {table_.handle()};
  VkDescriptorSet set = pool.allocate(*kernel, constants.handle(), storage);
  gpu::CommandStream stream(ctx);

  const auto start = std::chrono::steady_clock::now();
  VkCommandBuffer cmd = stream.begin();
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel->pipeline());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel->layout(), 0, 1, &set, 0, nullptr);
  vkCmdDispatch(cmd, kTexels / kWorkgroupSize, 1, 1);
  // Every later reader (passes in later submissions on this queue, read()'s copy).
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT);
  stream.submit_and_wait();
  compute_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::vector<float> FbLut::read() const {
  gpu::Buffer download(ctx_, kTableBytes, gpu::BufferKind::StorageDownload, "fb_lut:download");
  gpu::CommandStream stream(ctx_);
  VkCommandBuffer cmd = stream.begin();
  const VkBufferCopy region{0, 0, kTableBytes};
  vkCmdCopyBuffer(cmd, table_.handle(), download.handle(), 1, &region);
  download.record_readback(cmd, kTableBytes, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  stream.submit_and_wait();
  std::vector<float> values(size_t{kTexels} * 2);
  download.read({reinterpret_cast<uint8_t*>(values.data()), kTableBytes});
  return values;
}

const FbLut& fb_lut(gpu::Context& ctx) {
  return ctx.shared<FbLut>([&ctx] { return std::make_unique<FbLut>(ctx); });
}

const gpu::Buffer& fb_lut_buffer(gpu::Context& ctx) { return fb_lut(ctx).buffer(); }

}  // namespace dn::pipelines
