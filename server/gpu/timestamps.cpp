#include "gpu/timestamps.hpp"

#include "gpu/context.hpp"
#include "gpu/error.hpp"

namespace dn::gpu {

TimestampPool::TimestampPool(Context& context, uint32_t count)
    : device_(context.device()), count_(count), period_ns_(context.timestamp_period_ns()) {
  const uint32_t bits = context.timestamp_valid_bits();
  mask_ = bits >= 64 ? ~uint64_t{0} : ((uint64_t{1} << bits) - 1);
  if (bits == 0 || count == 0) return;
  VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  info.queryType = VK_QUERY_TYPE_TIMESTAMP;
  info.queryCount = count;
  check(vkCreateQueryPool(device_, &info, nullptr, &pool_), "vkCreateQueryPool");
}

TimestampPool::~TimestampPool() {
  if (pool_) vkDestroyQueryPool(device_, pool_, nullptr);
}

void TimestampPool::reset(VkCommandBuffer cmd) {
  if (pool_) vkCmdResetQueryPool(cmd, pool_, 0, count_);
}

void TimestampPool::write(VkCommandBuffer cmd, VkPipelineStageFlagBits stage, uint32_t index) {
  if (pool_ && index < count_) vkCmdWriteTimestamp(cmd, stage, pool_, index);
}

std::vector<double> TimestampPool::read_intervals_ms(uint32_t marks) {
  std::vector<double> out(marks > 0 ? marks - 1 : 0, 0.0);
  if (!pool_ || marks < 2) return out;
  if (marks > count_) throw Error("read_intervals_ms: more marks than timestamps");
  std::vector<uint64_t> ticks(marks);
  check(vkGetQueryPoolResults(device_, pool_, 0, marks, ticks.size() * sizeof(uint64_t), ticks.data(),
                              sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
        "vkGetQueryPoolResults");
  for (uint32_t i = 0; i + 1 < marks; ++i) {
    const uint64_t delta = ((ticks[i + 1] & mask_) - (ticks[i] & mask_)) & mask_;
    out[i] = static_cast<double>(delta) * period_ns_ * 1e-6;
  }
  return out;
}

}  // namespace dn::gpu
