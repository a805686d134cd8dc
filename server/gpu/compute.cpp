#include "gpu/compute.hpp"

#include <algorithm>
#include <chrono>

#include "gpu/context.hpp"
#include "gpu/error.hpp"

namespace dn::gpu {

namespace {

// The workgroup shape of a desc as (x, y), checked; (0, 0) when the caller
// sets constant 0 itself.
std::array<uint32_t, 2> checked_local_size(const KernelDesc& desc) {
  const std::string what = "kernel " + desc.name + ": ";
  if (desc.local_size_x == 0) {
    if (desc.local_size_y != 0) throw Error(what + "local_size_y without local_size_x");
    return {0, 0};
  }
  const uint32_t y = desc.local_size_y == 0 ? 1 : desc.local_size_y;
  // Square or 1-D only: both axes read constant 0 (see kLocalSizeId).
  if (y != 1 && y != desc.local_size_x)
    throw Error(what + "2-D workgroups are square (local_size_y must be 1 or local_size_x)");
  for (const auto& c : desc.spec_constants)
    if (c.id == kLocalSizeId) throw Error(what + "constant 0 given twice (local_size_x and spec_constants)");
  return {desc.local_size_x, y};
}

}  // namespace

Kernel::Kernel(VkDevice device, const KernelDesc& desc, VkPipelineCache cache)
    : device_(device), name_(desc.name), storage_buffers_(desc.storage_buffers), texel_formats_(desc.texel_formats),
      push_constant_bytes_(desc.push_constant_bytes) {
  if (desc.spirv.empty()) throw Error("kernel " + name_ + ": no SPIR-V (shader not embedded?)");
  if (!texel_formats_.empty() && texel_formats_.size() != storage_buffers_)
    throw Error("kernel " + name_ + ": " + std::to_string(texel_formats_.size()) + " texel formats for " +
                std::to_string(storage_buffers_) + " bindings");
  const auto local = checked_local_size(desc);
  local_size_x_ = local[0];
  local_size_y_ = local[1];
  if (push_constant_bytes_ % 4 != 0 || push_constant_bytes_ > kMaxPushConstantBytes)
    throw Error("kernel " + name_ + ": push_constant_bytes must be a multiple of 4 and at most " +
                std::to_string(kMaxPushConstantBytes));
  VkShaderModule module = VK_NULL_HANDLE;
  try {
    std::vector<VkDescriptorSetLayoutBinding> bindings(desc.storage_buffers + 1);
    for (uint32_t i = 0; i < bindings.size(); ++i) {
      bindings[i].binding = i;
      bindings[i].descriptorType = i > 0 && texel_format(i - 1) != VK_FORMAT_UNDEFINED
                                       ? VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER
                                       : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;  // 0 too: see BufferKind::Constants
      bindings[i].descriptorCount = 1;
      bindings[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    }
    VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    set_info.bindingCount = static_cast<uint32_t>(bindings.size());
    set_info.pBindings = bindings.data();
    check(vkCreateDescriptorSetLayout(device_, &set_info, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");

    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = 1;
    layout_info.pSetLayouts = &set_layout_;
    const VkPushConstantRange push_range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_constant_bytes_};
    if (push_constant_bytes_ > 0) {
      layout_info.pushConstantRangeCount = 1;
      layout_info.pPushConstantRanges = &push_range;
    }
    check(vkCreatePipelineLayout(device_, &layout_info, nullptr, &layout_), "vkCreatePipelineLayout");

    VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    module_info.codeSize = desc.spirv.size_bytes();
    module_info.pCode = desc.spirv.data();
    check(vkCreateShaderModule(device_, &module_info, nullptr, &module), "vkCreateShaderModule");

    std::vector<VkSpecializationMapEntry> entries;
    std::vector<uint32_t> data;
    std::vector<SpecConstant> constants = desc.spec_constants;
    if (local_size_x_ != 0) constants.push_back({kLocalSizeId, local_size_x_});
    for (const auto& c : constants) {
      entries.push_back({c.id, static_cast<uint32_t>(data.size() * sizeof(uint32_t)), sizeof(uint32_t)});
      data.push_back(c.value);
    }
    VkSpecializationInfo spec{};
    spec.mapEntryCount = static_cast<uint32_t>(entries.size());
    spec.pMapEntries = entries.data();
    spec.dataSize = data.size() * sizeof(uint32_t);
    spec.pData = data.data();

    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.stage.pSpecializationInfo = entries.empty() ? nullptr : &spec;
    info.layout = layout_;
    check(vkCreateComputePipelines(device_, cache, 1, &info, nullptr, &pipeline_),
          "vkCreateComputePipelines");
    vkDestroyShaderModule(device_, module, nullptr);
  } catch (...) {
    if (module) vkDestroyShaderModule(device_, module, nullptr);
    destroy();
    throw;
  }
}

Kernel::~Kernel() { destroy(); }

std::array<uint32_t, 2> Kernel::groups(uint32_t width, uint32_t height) const {
  if (local_size_x_ == 0) throw Error("kernel " + name_ + ": no workgroup shape (KernelDesc::local_size_x)");
  return {(width + local_size_x_ - 1) / local_size_x_, (height + local_size_y_ - 1) / local_size_y_};
}

void Kernel::record_push(VkCommandBuffer cmd, std::span<const uint8_t> bytes) const {
  if (bytes.size() > push_constant_bytes_ || bytes.size() % 4 != 0)
    throw Error("kernel " + name_ + ": " + std::to_string(bytes.size()) + " push-constant bytes, range is " +
                std::to_string(push_constant_bytes_));
  if (!bytes.empty())
    vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, static_cast<uint32_t>(bytes.size()),
                       bytes.data());
}

void Kernel::record_dispatch(VkCommandBuffer cmd, VkDescriptorSet set, const GridPush& grid) const {
  const auto g = groups(grid.size[0], grid.size[1]);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set, 0, nullptr);
  if (push_constant_bytes_ > 0) record_push(cmd, {reinterpret_cast<const uint8_t*>(&grid), sizeof grid});
  vkCmdDispatch(cmd, g[0], g[1], 1);
}

bool Kernel::prepared_at(uint32_t width, uint32_t height) const {
  std::lock_guard lock(prepared_mutex_);
  return prepared_sizes_.contains({width, height});
}

void Kernel::mark_prepared(uint32_t width, uint32_t height) const {
  std::lock_guard lock(prepared_mutex_);
  prepared_sizes_.insert({width, height});
  prepared_.store(true);
}

void Kernel::note_dispatch() const {
  if (dispatched_.load(std::memory_order_relaxed) || dispatched_.exchange(true)) return;
  if (!first_runs_) return;
  ++first_runs_->kernels;
  if (!prepared_.load()) ++first_runs_->unprepared;
}

void Kernel::destroy() noexcept {
  if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
  if (layout_) vkDestroyPipelineLayout(device_, layout_, nullptr);
  if (set_layout_) vkDestroyDescriptorSetLayout(device_, set_layout_, nullptr);
  pipeline_ = VK_NULL_HANDLE;
  layout_ = VK_NULL_HANDLE;
  set_layout_ = VK_NULL_HANDLE;
}

namespace {
thread_local double compile_ms_this_thread = 0.0;
thread_local KernelCache::Recording* recording = nullptr;
}  // namespace

std::shared_ptr<const Kernel> KernelCache::recorded(std::shared_ptr<const Kernel> kernel) {
  if (recording) recording->kernels_.push_back(kernel);
  return kernel;
}

KernelCache::Recording::Recording() : outer_(recording) { recording = this; }
KernelCache::Recording::~Recording() { recording = outer_; }

double KernelCache::compile_ms_of_this_thread() { return compile_ms_this_thread; }

std::shared_ptr<const Kernel> KernelCache::get(const KernelDesc& desc) {
  Key key{desc.spirv.data(), desc.spirv.size(), desc.storage_buffers, desc.spec_constants,
          desc.local_size_x, desc.local_size_y, desc.push_constant_bytes, desc.texel_formats};
  std::promise<std::shared_ptr<const Kernel>> promise;
  std::shared_future<std::shared_ptr<const Kernel>> compiled_elsewhere;
  {
    std::lock_guard lock(mutex_);
    auto it = kernels_.find(key);
    if (it != kernels_.end())
      compiled_elsewhere = it->second;
    else
      kernels_.emplace(key, promise.get_future().share());
  }
  if (compiled_elsewhere.valid()) return recorded(compiled_elsewhere.get());  // waits if it is still compiling
  const auto start = std::chrono::steady_clock::now();
  std::shared_ptr<Kernel> kernel;
  try {
    kernel = std::make_shared<Kernel>(device_, desc, pipeline_cache_);
    kernel->first_runs_ = &first_runs_;
  } catch (...) {
    std::lock_guard lock(mutex_);
    kernels_.erase(key);  // the next caller tries again
    promise.set_exception(std::current_exception());
    throw;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  compile_ms_this_thread += ms;
  {
    std::lock_guard lock(mutex_);
    ++stats_.kernels;
    stats_.total_ms += ms;
    stats_.slowest_ms = std::max(stats_.slowest_ms, ms);
  }
  promise.set_value(kernel);
  return recorded(kernel);
}

CompileStats KernelCache::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void KernelCache::keep_current() {
  std::lock_guard lock(mutex_);
  for (const auto& [key, kernel] : kernels_)
    if (kernel.wait_for(std::chrono::seconds(0)) == std::future_status::ready) kept_.insert(kernel.get().get());
}

size_t KernelCache::drop_unused() {
  std::vector<std::shared_future<std::shared_ptr<const Kernel>>> doomed;  // destroyed after the lock is released
  {
    std::lock_guard lock(mutex_);
    for (auto it = kernels_.begin(); it != kernels_.end();) {
      // A compile that failed is never left here ready, so get() does not throw; the
      // cache's own reference is the only one when no pipeline holds the kernel.
      const bool ready = it->second.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
      if (ready && !kept_.contains(it->second.get().get()) && it->second.get().use_count() == 1) {
        doomed.push_back(std::move(it->second));
        it = kernels_.erase(it);
      } else {
        ++it;
      }
    }
  }
  return doomed.size();
}

size_t KernelCache::size() const {
  std::lock_guard lock(mutex_);
  return kernels_.size();
}

DescriptorPool::DescriptorPool(Context& context, uint32_t sets, uint32_t storage_buffers_total)
    : device_(context.device()) {
  // Each set's constants (binding 0) and its buffers, any of which may be a
  // storage buffer or a texel buffer.
  const VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, sets + storage_buffers_total},
                                         {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, std::max(1u, storage_buffers_total)}};
  VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  info.maxSets = sets;
  info.poolSizeCount = 2;
  info.pPoolSizes = sizes;
  check(vkCreateDescriptorPool(device_, &info, nullptr, &pool_), "vkCreateDescriptorPool");
}

DescriptorPool::~DescriptorPool() {
  for (auto& [set, views] : views_)
    for (VkBufferView v : views) vkDestroyBufferView(device_, v, nullptr);
  if (pool_) vkDestroyDescriptorPool(device_, pool_, nullptr);
}

VkDescriptorSet DescriptorPool::allocate(const Kernel& kernel, VkBuffer constants, std::span<const VkBuffer> storage) {
  if (storage.size() != kernel.storage_buffers())
    throw Error("kernel " + kernel.name() + ": " + std::to_string(storage.size()) + " storage buffers given, " +
                std::to_string(kernel.storage_buffers()) + " expected");
  VkDescriptorSetLayout layout = kernel.set_layout();
  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = pool_;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &layout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  check(vkAllocateDescriptorSets(device_, &alloc, &set), "vkAllocateDescriptorSets");
  write(set, kernel, constants, storage);
  return set;
}

void DescriptorPool::write(VkDescriptorSet set, const Kernel& kernel, VkBuffer constants,
                           std::span<const VkBuffer> storage) {
  if (storage.size() != kernel.storage_buffers())
    throw Error("kernel " + kernel.name() + ": " + std::to_string(storage.size()) + " storage buffers given, " +
                std::to_string(kernel.storage_buffers()) + " expected");
  std::vector<VkDescriptorBufferInfo> infos(storage.size() + 1);
  std::vector<VkBufferView> views(storage.size() + 1, VK_NULL_HANDLE);
  std::vector<VkWriteDescriptorSet> writes(storage.size() + 1);
  try {
    for (size_t i = 0; i < infos.size(); ++i) {
      const VkFormat texel = i == 0 ? VK_FORMAT_UNDEFINED : kernel.texel_format(static_cast<uint32_t>(i - 1));
      writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[i].dstSet = set;
      writes[i].dstBinding = static_cast<uint32_t>(i);
      writes[i].descriptorCount = 1;
      if (texel == VK_FORMAT_UNDEFINED) {
        infos[i] = {i == 0 ? constants : storage[i - 1], 0, VK_WHOLE_SIZE};
        writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[i].pBufferInfo = &infos[i];
      } else {
        VkBufferViewCreateInfo vi{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
        vi.buffer = storage[i - 1];
        vi.format = texel;
        vi.range = VK_WHOLE_SIZE;
        check(vkCreateBufferView(device_, &vi, nullptr, &views[i]), "vkCreateBufferView");
        writes[i].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
        writes[i].pTexelBufferView = &views[i];
      }
    }
  } catch (...) {
    for (VkBufferView v : views)
      if (v) vkDestroyBufferView(device_, v, nullptr);
    throw;
  }
  vkUpdateDescriptorSets(device_, static_cast<uint32_t>(writes.size()), writes.data(), 0, nullptr);
  // The set no longer refers to its old views (and is idle: see write()).
  auto& owned = views_[set];
  for (VkBufferView v : owned) vkDestroyBufferView(device_, v, nullptr);
  owned.clear();
  for (VkBufferView v : views)
    if (v) owned.push_back(v);
}

}  // namespace dn::gpu
