// Compute kernels: a SPIR-V module specialised into a VkPipeline, with its
// descriptor-set layout (binding 0: uniform buffer, bindings 1..n: storage
// buffers) and pipeline layout. Kernels are immutable and shared: the
// Context's KernelCache hands out one per (module, binding count,
// specialization constants), so sessions with the same formats and shader
// compile it once.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <tuple>
#include <vector>

namespace dn::gpu {

class Context;

struct SpecConstant {
  uint32_t id = 0;
  uint32_t value = 0;  // 32-bit: uint, bool (0/1) or float bits
  auto operator<=>(const SpecConstant&) const = default;
};

struct KernelDesc {
  std::string name;                  // for error messages
  std::span<const uint32_t> spirv;
  uint32_t storage_buffers = 0;      // bindings 1..storage_buffers
  std::vector<SpecConstant> spec_constants;
};

class Kernel {
 public:
  // cache: a VkPipelineCache the driver may reuse compiled code from (or VK_NULL_HANDLE).
  Kernel(VkDevice device, const KernelDesc& desc, VkPipelineCache cache = VK_NULL_HANDLE);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  const std::string& name() const { return name_; }
  uint32_t storage_buffers() const { return storage_buffers_; }
  VkDescriptorSetLayout set_layout() const { return set_layout_; }
  VkPipelineLayout layout() const { return layout_; }
  VkPipeline pipeline() const { return pipeline_; }

 private:
  void destroy() noexcept;
  VkDevice device_;
  std::string name_;
  uint32_t storage_buffers_;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
};

// What compiling has cost so far (for STATS and the benchmarks).
struct CompileStats {
  uint64_t kernels = 0;      // pipelines created
  double total_ms = 0.0;     // wall time spent in vkCreateComputePipelines and friends
  double slowest_ms = 0.0;   // the slowest single kernel
};

class KernelCache {
 public:
  explicit KernelCache(VkDevice device, VkPipelineCache pipeline_cache = VK_NULL_HANDLE)
      : device_(device), pipeline_cache_(pipeline_cache) {}
  // Thread-safe. Compiles on first use, outside the cache's lock: threads
  // compiling different kernels run in parallel, and a thread asking for a
  // kernel another thread is compiling waits for that one kernel only.
  std::shared_ptr<const Kernel> get(const KernelDesc& desc);
  size_t size() const;
  CompileStats stats() const;
  // Milliseconds the calling thread has spent compiling (in any cache).
  static double compile_ms_of_this_thread();

 private:
  using Key = std::tuple<const uint32_t*, size_t, uint32_t, std::vector<SpecConstant>>;
  VkDevice device_;
  VkPipelineCache pipeline_cache_;
  mutable std::mutex mutex_;
  std::map<Key, std::shared_future<std::shared_ptr<const Kernel>>> kernels_;
  CompileStats stats_;
};

// Descriptor sets of one pipeline instance: a pool sized for `sets` sets of
// kernels with up to `storage_per_set` storage buffers each.
class DescriptorPool {
 public:
  DescriptorPool(Context& context, uint32_t sets, uint32_t storage_buffers_total);
  ~DescriptorPool();
  DescriptorPool(const DescriptorPool&) = delete;
  DescriptorPool& operator=(const DescriptorPool&) = delete;

  // Allocates and writes a set: binding 0 = uniform, 1.. = storage (whole buffers).
  VkDescriptorSet allocate(const Kernel& kernel, VkBuffer uniform, std::span<const VkBuffer> storage);

 private:
  VkDevice device_;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
};

}  // namespace dn::gpu
