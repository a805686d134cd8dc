// GraphPipeline's inspection for tests and debugging (set_capture): every
// binding a pass wrote or read, copied after the pass into a host-readable buffer.
#include "pipelines/graph.hpp"

#include <stdexcept>

namespace dn::pipelines {

void GraphPipeline::set_capture(bool on) {
  std::lock_guard lock(mutex_);
  for (auto& pass : passes_) {
    pass.captures.clear();
    if (!on) continue;
    for (const auto& ref : pass.spec->bindings()) {
      if (!ref.bound()) continue;
      const BufferSpec* b = spec_->find(ref.buffer);
      if (b->role == BufferRole::Input || b->role == BufferRole::Shared || b->role == BufferRole::Constant) continue;
      pass.captures.push_back({ref.buffer, ref.slot,
                               gpu::Buffer(context_, b->bytes, gpu::BufferKind::StorageDownload,
                                           pass.spec->name() + ":" + ref.buffer)});
    }
  }
}

std::vector<uint8_t> GraphPipeline::captured(const std::string& pass, const std::string& buffer) const {
  for (const auto& p : passes_) {
    if (p.spec->name() != pass) continue;
    for (const auto& c : p.captures) {
      if (c.buffer != buffer) continue;
      std::vector<uint8_t> bytes(c.copy.size());
      c.copy.read(bytes);
      return bytes;
    }
  }
  throw std::out_of_range("pipeline graph: nothing captured for buffer " + buffer + " after pass " + pass);
}

// After the pass: copy each captured binding (and, when the capture buffer is
// staged, on to its host-visible copy); the next pass waits for the copies
// before it may overwrite what they read.
void GraphPipeline::record_captures(VkCommandBuffer cmd, const Pass& pass, uint32_t parity) {
  if (pass.captures.empty()) return;
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                      VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
  for (const auto& c : pass.captures) {
    const VkBufferCopy region{0, 0, c.copy.size()};
    vkCmdCopyBuffer(cmd, bound({c.buffer, c.slot}, parity).handle(), c.copy.handle(), 1, &region);
  }
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                      VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
  for (const auto& c : pass.captures) c.copy.record_download(cmd, c.copy.size());
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_HOST_READ_BIT);
}

}  // namespace dn::pipelines
