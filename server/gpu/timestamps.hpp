// Timestamp queries: a pool of `count` timestamps written by the command
// buffer and read back as milliseconds between consecutive marks.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <vector>

namespace dn::gpu {

class Context;

class TimestampPool {
 public:
  TimestampPool(Context& context, uint32_t count);
  ~TimestampPool();
  TimestampPool(const TimestampPool&) = delete;
  TimestampPool& operator=(const TimestampPool&) = delete;

  // False when the queue has no timestamps; write() is then a no-op and
  // read_intervals_ms() returns zeros.
  bool supported() const { return pool_ != VK_NULL_HANDLE; }
  // Must be recorded before the first write() of a submission.
  void reset(VkCommandBuffer cmd);
  void write(VkCommandBuffer cmd, VkPipelineStageFlagBits stage, uint32_t index);
  // After the submission completed: ms between marks i and i + 1 for i < marks - 1.
  std::vector<double> read_intervals_ms(uint32_t marks);

 private:
  VkDevice device_;
  uint32_t count_;
  double period_ns_;
  uint64_t mask_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
};

}  // namespace dn::gpu
