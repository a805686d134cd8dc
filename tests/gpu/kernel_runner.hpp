// Running a 2-D test kernel (grid2d.glsl) on the test context: buffers from
// host vectors, a list of dispatches with a barrier after each, readback.
#pragma once

#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"

namespace dn::test {

// The shared layout of probe kernels: square workgroup, GridPush constants.
inline gpu::KernelDesc grid_kernel_desc(std::string name, std::span<const uint32_t> spirv, uint32_t storage_buffers,
                                        uint32_t block, std::vector<gpu::SpecConstant> constants = {}) {
  gpu::KernelDesc desc;
  desc.name = std::move(name);
  desc.spirv = spirv;
  desc.storage_buffers = storage_buffers;
  desc.spec_constants = std::move(constants);
  desc.local_size_x = block;
  desc.local_size_y = block;
  desc.push_constant_bytes = sizeof(gpu::GridPush);
  return desc;
}

template <class T>
std::unique_ptr<gpu::Buffer> upload(gpu::Context& ctx, const std::vector<T>& values, const std::string& name) {
  const uint64_t bytes = values.size() * sizeof(T);
  auto b = std::make_unique<gpu::Buffer>(ctx, bytes, gpu::BufferKind::StorageUpload, name);
  b->write({reinterpret_cast<const uint8_t*>(values.data()), bytes});
  return b;
}

template <class T>
std::unique_ptr<gpu::Buffer> output(gpu::Context& ctx, size_t count, const std::string& name) {
  return std::make_unique<gpu::Buffer>(ctx, count * sizeof(T), gpu::BufferKind::StorageDownload, name);
}

template <class T>
std::vector<T> read(const gpu::Buffer& b) {
  std::vector<T> out(b.size() / sizeof(T));
  b.read({reinterpret_cast<uint8_t*>(out.data()), out.size() * sizeof(T)});
  return out;
}

// Records `before` (uploads, copies: it ends in transfer writes), then the
// dispatches in order with a compute barrier after each, then the readback
// of `outputs`; submits and waits. `bindings`: the kernel's storage buffers.
inline void run_grid_kernel(gpu::Context& ctx, const gpu::Kernel& kernel, const std::vector<const gpu::Buffer*>& bindings,
                            const std::vector<gpu::GridPush>& dispatches,
                            const std::vector<const gpu::Buffer*>& uploads,
                            const std::vector<const gpu::Buffer*>& outputs,
                            const std::function<void(VkCommandBuffer)>& before = {}) {
  gpu::Buffer uniform(ctx, 256, gpu::BufferKind::Constants, "unused_frame_constants");  // binding 0 of every kernel
  gpu::DescriptorPool pool(ctx, 1, static_cast<uint32_t>(bindings.size()));
  std::vector<VkBuffer> handles;
  for (const auto* b : bindings) handles.push_back(b->handle());
  VkDescriptorSet set = pool.allocate(kernel, uniform.handle(), handles);

  gpu::CommandStream stream(ctx);
  VkCommandBuffer cmd = stream.begin();
  for (const auto* b : uploads) b->record_upload(cmd, b->size());
  if (before) before(cmd);
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  for (const auto& grid : dispatches) {
    kernel.record_dispatch(cmd, set, grid);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  }
  for (const auto* b : outputs)
    b->record_readback(cmd, b->size(), VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
  stream.submit_and_wait();
}

inline gpu::GridPush grid(uint32_t width, uint32_t height) {
  gpu::GridPush g;
  g.size[0] = g.source[0] = width;
  g.size[1] = g.source[1] = height;
  return g;
}

}  // namespace dn::test
