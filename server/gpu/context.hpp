// dn::gpu::Context: the Vulkan instance, the chosen physical device, one
// logical device with one compute queue, optional validation, and the cache
// of compute kernels. One per server process; it must outlive every buffer,
// kernel and command stream created from it.
//
// Thread safety: submit() is serialised by a mutex (vkQueueSubmit needs the
// queue externally synchronised); everything else a Context hands out is
// either immutable or owned by one pipeline.
#pragma once

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <typeindex>
#include <unordered_map>
#include <vector>

#include "gpu/devices.hpp"
#include "gpu/limits.hpp"

namespace dn::gpu {

class KernelCache;
class PipelineCache;

struct ContextOptions {
  // Device selector (see select_device): empty, an index, or a name substring.
  std::string device;
  // Enables VK_LAYER_KHRONOS_validation with a debug-utils messenger. The
  // environment variable DN_VALIDATION=1 turns it on as well. When the layer
  // is not installed the context runs without it (validation_enabled() false).
  bool validation = false;
  // With validation: also enable synchronization validation.
  bool synchronization_validation = false;
  // With validation: print every counted message to stderr.
  bool print_validation_messages = true;
  // Testing: reach upload/download buffers through staging buffers even where
  // device memory is host-visible (exercises the discrete-GPU path on lavapipe).
  bool force_staging = false;
  // Directory of the on-disk VkPipelineCache (gpu/pipeline_cache.hpp); empty:
  // compiled pipelines are cached in memory only.
  std::string pipeline_cache_dir;
};

class Context {
 public:
  explicit Context(const ContextOptions& options = {});
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Every physical device the loader reports (creates a temporary instance).
  static std::vector<DeviceInfo> list_devices();
  // Whether VK_LAYER_KHRONOS_validation is installed.
  static bool validation_layer_available();

  const std::string& name() const { return info_.name; }
  // What it was made with (a private context for the same device copies them).
  const ContextOptions& options() const { return options_; }
  const DeviceInfo& info() const { return info_; }
  const DeviceLimits& limits() const { return limits_; }

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_; }
  VkDevice device() const { return device_; }
  uint32_t queue_family() const { return queue_family_; }
  const VkPhysicalDeviceMemoryProperties& memory_properties() const { return memory_; }
  const VkPhysicalDeviceProperties& properties() const { return properties_; }

  // Timestamps: nanoseconds per tick, and the valid bits of the compute queue
  // (0 = the queue has no timestamps; passes then report 0 ms).
  double timestamp_period_ns() const { return properties_.limits.timestampPeriod; }
  uint32_t timestamp_valid_bits() const { return timestamp_bits_; }

  bool validation_enabled() const { return messenger_ != VK_NULL_HANDLE; }
  bool force_staging() const { return force_staging_; }
  // Validation messages of severity WARNING or ERROR received so far.
  uint64_t validation_message_count() const { return validation_->count.load(); }
  // The most recent of those messages (at most 64).
  std::vector<std::string> validation_messages() const;

  // vkQueueSubmit under the queue mutex. Throws VulkanError; a device loss
  // marks the context lost, after which every submit fails immediately.
  void submit(VkCommandBuffer command_buffer, VkFence fence);
  bool lost() const { return lost_.load(); }
  void mark_lost() { lost_.store(true); }

  KernelCache& kernels() { return *kernels_; }
  PipelineCache& pipeline_cache() { return *pipeline_cache_; }

  // Per-context shared resources, one object per type T (e.g. the F_beta
  // table, pipelines::fb_lut): the first call makes it with `make`, later
  // calls return the same object. Thread-safe: concurrent first callers wait
  // for the one construction (a recursive mutex, so `make` may itself ask for
  // another type); if `make` throws, nothing is stored and the next call
  // tries again. Destroyed before the device (and the kernel cache).
  template <class T>
  T& shared(const std::function<std::unique_ptr<T>()>& make) {
    std::lock_guard lock(shared_mutex_);
    std::shared_ptr<void>& slot = shared_[std::type_index(typeid(T))];
    if (!slot) slot = std::shared_ptr<T>(make());
    return *static_cast<T*>(slot.get());
  }

  struct ValidationState {
    std::atomic<uint64_t> count{0};
    bool print = true;
    mutable std::mutex mutex;
    std::deque<std::string> recent;
  };

 private:
  void create_instance(bool validation, bool sync_validation);
  void create_device();

  ContextOptions options_;
  std::unique_ptr<ValidationState> validation_;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  uint32_t timestamp_bits_ = 0;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  DeviceLimits limits_;
  std::mutex submit_mutex_;
  std::atomic<bool> lost_{false};
  bool force_staging_ = false;
  std::unique_ptr<PipelineCache> pipeline_cache_;
  std::unique_ptr<KernelCache> kernels_;
  std::recursive_mutex shared_mutex_;
  std::unordered_map<std::type_index, std::shared_ptr<void>> shared_;
};

}  // namespace dn::gpu
