#include "gpu/commands.hpp"

#include "gpu/context.hpp"
#include "gpu/error.hpp"

namespace dn::gpu {

CommandStream::CommandStream(Context& context) : context_(context) {
  VkDevice device = context.device();
  try {
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT | VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    pool.queueFamilyIndex = context.queue_family();
    check(vkCreateCommandPool(device, &pool, nullptr, &pool_), "vkCreateCommandPool");

    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(device, &alloc, &cmd_), "vkAllocateCommandBuffers");

    VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(device, &fence, nullptr, &fence_), "vkCreateFence");
  } catch (...) {
    if (pool_) vkDestroyCommandPool(device, pool_, nullptr);
    throw;
  }
}

CommandStream::~CommandStream() {
  wait_pending();
  VkDevice device = context_.device();
  if (fence_) vkDestroyFence(device, fence_, nullptr);
  if (pool_) vkDestroyCommandPool(device, pool_, nullptr);  // frees cmd_
}

void CommandStream::wait_pending() noexcept {
  if (!pending_) return;
  // Returns promptly on a lost device; otherwise the work must finish before
  // its command buffer may be reset or freed.
  const VkResult r = vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, UINT64_MAX);
  if (r == VK_ERROR_DEVICE_LOST) context_.mark_lost();
  pending_ = false;
}

VkCommandBuffer CommandStream::begin() {
  wait_pending();
  if (context_.lost()) throw VulkanError(VK_ERROR_DEVICE_LOST, "CommandStream::begin");
  check(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd_, &info), "vkBeginCommandBuffer");
  return cmd_;
}

void CommandStream::submit_and_wait(uint64_t timeout_ns) {
  check(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
  check(vkResetFences(context_.device(), 1, &fence_), "vkResetFences");
  context_.submit(cmd_, fence_);
  pending_ = true;
  const VkResult r = vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, timeout_ns);
  if (r == VK_SUCCESS) {
    pending_ = false;
    return;
  }
  if (r == VK_ERROR_DEVICE_LOST) {
    context_.mark_lost();
    pending_ = false;
  }
  throw VulkanError(r, "vkWaitForFences");
}

void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                    VkPipelineStageFlags dst_stage, VkAccessFlags dst_access) {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = src_access;
  barrier.dstAccessMask = dst_access;
  vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

}  // namespace dn::gpu
