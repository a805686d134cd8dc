// One command buffer with its pool and fence, recorded and submitted once
// per frame by the pipeline that owns it, plus the barrier helper passes use.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>

namespace dn::gpu {

class Context;

class CommandStream {
 public:
  explicit CommandStream(Context& context);
  ~CommandStream();
  CommandStream(const CommandStream&) = delete;
  CommandStream& operator=(const CommandStream&) = delete;

  // Resets and begins the command buffer (one-time submit).
  VkCommandBuffer begin();
  // Ends, submits through the Context and waits for the fence. On timeout
  // or device loss throws VulkanError (device loss also marks the Context
  // lost); a timed-out submission stays pending and is waited for before
  // the next begin() or destruction.
  void submit_and_wait(uint64_t timeout_ns = kDefaultTimeoutNs);

  static constexpr uint64_t kDefaultTimeoutNs = 60ull * 1000 * 1000 * 1000;
  // For a submission that is the first use of its pipelines: lavapipe
  // JIT-compiles each at its first dispatch, inside the wait (a cold-cache
  // first reflect frame: 77-89 s on a 2-core VM).
  static constexpr uint64_t kFirstUseTimeoutNs = 600ull * 1000 * 1000 * 1000;

 private:
  void wait_pending() noexcept;
  Context& context_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  bool pending_ = false;
};

// Global memory barrier between two stages.
void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                    VkPipelineStageFlags dst_stage, VkAccessFlags dst_access);

}  // namespace dn::gpu
