// Compute kernels: a SPIR-V module specialised into a VkPipeline, with its
// descriptor-set layout (binding 0: the frame constants, a storage buffer,
// see BufferKind::Constants; bindings 1..n: the pass's buffers, storage
// buffers or uniform texel buffers) and pipeline layout. Kernels are immutable and shared: the
// Context's KernelCache hands out one per (module, binding count,
// specialization constants, workgroup shape, push-constant size), so
// sessions with the same formats and shader compile it once.
//
// 2-D kernels (shaders/include/grid2d.glsl) set KernelDesc::local_size_x/y
// and push_constant_bytes: the workgroup's shape becomes specialization
// constant 0 and each dispatch pushes its grid (GridPush), so a pass at a
// reduced resolution knows its grid without constants of its own.
#pragma once

#include <vulkan/vulkan.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <vector>

namespace dn::gpu {

class Context;
struct FirstRunCounter;

struct SpecConstant {
  uint32_t id = 0;
  uint32_t value = 0;  // 32-bit: uint, bool (0/1) or float bits
  auto operator<=>(const SpecConstant&) const = default;
};

// The workgroup's x size is specialization constant 0 in every shader
// (local_size_x_id = 0). 2-D shaders declare local_size_y_id = 0 as well:
// square workgroups, because tests/pipelines' SPIR-V reflection check admits
// no constant id outside a pass declaration but 0.
inline constexpr uint32_t kLocalSizeId = 0;
// Push constants a kernel may declare: Vulkan's guaranteed minimum.
inline constexpr uint32_t kMaxPushConstantBytes = 128;

struct KernelDesc {
  std::string name;                  // for error messages
  std::span<const uint32_t> spirv;
  uint32_t storage_buffers = 0;      // bindings 1..storage_buffers
  // Empty, or one per binding 1..storage_buffers: VK_FORMAT_UNDEFINED for a
  // storage buffer, else the binding is a uniform texel buffer and the
  // DescriptorPool views the bound buffer in this format.
  std::vector<VkFormat> texel_formats;
  std::vector<SpecConstant> spec_constants;
  // Workgroup shape. 0 (the default): the caller sets constant 0 itself in
  // spec_constants and the kernel is 1-D, as every pass before 2-D kernels.
  // Otherwise constant 0 = local_size_x, and local_size_y is 1 (1-D) or
  // equal to local_size_x (square 2-D workgroup, grid2d.glsl).
  uint32_t local_size_x = 0;
  uint32_t local_size_y = 0;
  // Size of the push-constant range (compute stage, offset 0; a multiple of
  // 4, at most kMaxPushConstantBytes); 0: none.
  uint32_t push_constant_bytes = 0;
};

// The push constants of grid2d.glsl (DnGrid, 32 bytes): the grid a dispatch
// writes, the grid it reads, and four free per-dispatch values.
struct GridPush {
  uint32_t size[2] = {0, 0};    // width, height of the grid written
  uint32_t source[2] = {0, 0};  // width, height of the grid read (a pyramid's finer level; else = size)
  uint32_t args[4] = {0, 0, 0, 0};
};
static_assert(sizeof(GridPush) == 32);

class Kernel {
 public:
  // cache: a VkPipelineCache the driver may reuse compiled code from (or VK_NULL_HANDLE).
  Kernel(VkDevice device, const KernelDesc& desc, VkPipelineCache cache = VK_NULL_HANDLE);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  const std::string& name() const { return name_; }
  uint32_t storage_buffers() const { return storage_buffers_; }
  // Binding i + 1's texel format (VK_FORMAT_UNDEFINED: a storage buffer).
  VkFormat texel_format(uint32_t i) const { return i < texel_formats_.size() ? texel_formats_[i] : VK_FORMAT_UNDEFINED; }
  VkDescriptorSetLayout set_layout() const { return set_layout_; }
  VkPipelineLayout layout() const { return layout_; }
  // For recording a dispatch (its only use): the first call counts the
  // kernel's first run on this device (KernelCache::first_runs).
  VkPipeline pipeline() const {
    note_dispatch();
    return pipeline_;
  }
  // Whether a dispatch of this kernel has been recorded on this device.
  bool dispatched() const { return dispatched_.load(); }
  // Prepared: run once off the frame path at a session's frame size (the
  // warm-up, or a run on a private device whose machine code reaches this one
  // through Mesa's shader cache). Per size: lavapipe makes new machine code
  // for some frame sizes.
  bool prepared() const { return prepared_.load(); }  // at any size
  bool prepared_at(uint32_t width, uint32_t height) const;
  void mark_prepared(uint32_t width, uint32_t height) const;
  // Workgroup shape (x, y); (0, 0) for kernels whose constant 0 the caller set.
  std::array<uint32_t, 2> local_size() const { return {local_size_x_, local_size_y_}; }
  uint32_t push_constant_bytes() const { return push_constant_bytes_; }

  // Workgroups covering a width x height grid with this kernel's shape.
  std::array<uint32_t, 2> groups(uint32_t width, uint32_t height) const;
  // Records push constants (bytes.size() <= push_constant_bytes()).
  void record_push(VkCommandBuffer cmd, std::span<const uint8_t> bytes) const;
  // Binds the pipeline and `set`, pushes `grid` (when the kernel has push
  // constants: then at least sizeof(GridPush) bytes) and dispatches the
  // groups covering grid.size: one invocation per pixel of a 2-D kernel.
  void record_dispatch(VkCommandBuffer cmd, VkDescriptorSet set, const GridPush& grid) const;

 private:
  friend class KernelCache;
  void destroy() noexcept;
  void note_dispatch() const;
  VkDevice device_;
  std::string name_;
  uint32_t storage_buffers_;
  std::vector<VkFormat> texel_formats_;
  uint32_t local_size_x_ = 0;
  uint32_t local_size_y_ = 0;
  uint32_t push_constant_bytes_ = 0;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  mutable std::atomic<bool> dispatched_{false};
  mutable std::atomic<bool> prepared_{false};
  mutable std::mutex prepared_mutex_;
  mutable std::set<std::pair<uint32_t, uint32_t>> prepared_sizes_;
  FirstRunCounter* first_runs_ = nullptr;  // the cache's, set when it hands the kernel out
};

// First runs on one device. Lavapipe JIT-compiles a kernel's machine code at
// its first dispatch, inside the one queue every session shares, so a first
// run that was not prepared stalls every other session's frames meanwhile.
struct FirstRunStats {
  uint64_t kernels = 0;     // kernels dispatched at least once
  uint64_t unprepared = 0;  // of which the first dispatch came before any preparing run
};

struct FirstRunCounter {
  std::atomic<uint64_t> kernels{0};
  std::atomic<uint64_t> unprepared{0};
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
  // Bounds what compiled kernels keep while idle: keep_current() marks every
  // kernel compiled so far (the warm-up's) as kept for the cache's lifetime;
  // drop_unused() destroys the others that no pipeline holds now (a later
  // session compiles them again) and returns how many it destroyed.
  void keep_current();
  size_t drop_unused();
  CompileStats stats() const;
  FirstRunStats first_runs() const { return {first_runs_.kernels.load(), first_runs_.unprepared.load()}; }
  // Milliseconds the calling thread has spent compiling (in any cache).
  static double compile_ms_of_this_thread();

  // While one lives, every kernel the calling thread gets (from any cache,
  // compiled or found) is listed: the kernels a pipeline being built uses.
  class Recording {
   public:
    Recording();
    ~Recording();
    Recording(const Recording&) = delete;
    Recording& operator=(const Recording&) = delete;
    const std::vector<std::shared_ptr<const Kernel>>& kernels() const { return kernels_; }

   private:
    friend class KernelCache;
    std::vector<std::shared_ptr<const Kernel>> kernels_;
    Recording* outer_;
  };

 private:
  static std::shared_ptr<const Kernel> recorded(std::shared_ptr<const Kernel> kernel);
  using Key = std::tuple<const uint32_t*, size_t, uint32_t, std::vector<SpecConstant>, uint32_t, uint32_t, uint32_t,
                         std::vector<VkFormat>>;
  VkDevice device_;
  VkPipelineCache pipeline_cache_;
  mutable std::mutex mutex_;
  std::map<Key, std::shared_future<std::shared_ptr<const Kernel>>> kernels_;
  std::set<const Kernel*> kept_;
  CompileStats stats_;
  FirstRunCounter first_runs_;
};

// Descriptor sets of one pipeline instance: a pool sized for `sets` sets of
// kernels with `storage_buffers_total` buffer bindings in all (storage or
// texel). It owns the texel buffer views its sets use: a set's views are
// made when it is written and destroyed when it is rewritten or the pool goes.
class DescriptorPool {
 public:
  DescriptorPool(Context& context, uint32_t sets, uint32_t storage_buffers_total);
  ~DescriptorPool();
  DescriptorPool(const DescriptorPool&) = delete;
  DescriptorPool& operator=(const DescriptorPool&) = delete;

  // Allocates and writes a set: binding 0 = constants, 1.. = the buffers
  // (whole; a texel binding views the whole buffer in its format).
  VkDescriptorSet allocate(const Kernel& kernel, VkBuffer constants, std::span<const VkBuffer> storage);
  // Rewrites a set allocated for `kernel` to other buffers (e.g. when the
  // transient buffers leased for a frame are not last frame's). The set must
  // not be in use by a pending submission.
  void write(VkDescriptorSet set, const Kernel& kernel, VkBuffer constants, std::span<const VkBuffer> storage);

 private:
  VkDevice device_;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  std::map<VkDescriptorSet, std::vector<VkBufferView>> views_;
};

}  // namespace dn::gpu
