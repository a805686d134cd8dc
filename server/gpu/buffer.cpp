#include "gpu/buffer.hpp"

#include <bit>
#include <cstring>
#include <utility>

#include "gpu/commands.hpp"
#include "gpu/context.hpp"
#include "gpu/error.hpp"

namespace dn::gpu {
namespace {

constexpr VkMemoryPropertyFlags kDeviceLocal = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
constexpr VkMemoryPropertyFlags kHostVisible = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
constexpr VkMemoryPropertyFlags kHostCoherent = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
constexpr VkMemoryPropertyFlags kHostCached = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;

VkBuffer make_buffer(VkDevice device, uint64_t size, VkBufferUsageFlags usage) {
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer = VK_NULL_HANDLE;
  check(vkCreateBuffer(device, &info, nullptr, &buffer), "vkCreateBuffer");
  return buffer;
}

bool is_out_of_memory(VkResult r) {
  return r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY;
}

}  // namespace

int find_memory_type(const VkPhysicalDeviceMemoryProperties& props, uint32_t type_bits,
                     VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) {
  int best = -1;
  int best_score = -1;
  for (uint32_t i = 0; i < props.memoryTypeCount; ++i) {
    if (!(type_bits & (1u << i))) continue;
    const VkMemoryPropertyFlags flags = props.memoryTypes[i].propertyFlags;
    if ((flags & required) != required) continue;
    const int score = std::popcount(flags & preferred);
    if (score > best_score) {
      best = static_cast<int>(i);
      best_score = score;
    }
  }
  return best;
}

void Buffer::allocate(VkBuffer buffer, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                      VkDeviceMemory& memory, VkMemoryPropertyFlags& flags) const {
  VkMemoryRequirements req{};
  vkGetBufferMemoryRequirements(device_, buffer, &req);
  const int type = find_memory_type(*memory_props_, req.memoryTypeBits, required, preferred);
  if (type < 0) throw VulkanError(VK_ERROR_FEATURE_NOT_PRESENT, "find_memory_type(" + name_ + ")");
  VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  info.allocationSize = req.size;
  info.memoryTypeIndex = static_cast<uint32_t>(type);
  check(vkAllocateMemory(device_, &info, nullptr, &memory), "vkAllocateMemory");
  flags = memory_props_->memoryTypes[type].propertyFlags;
  const VkResult r = vkBindBufferMemory(device_, buffer, memory, 0);
  if (r != VK_SUCCESS) {
    vkFreeMemory(device_, memory, nullptr);
    memory = VK_NULL_HANDLE;
    check(r, "vkBindBufferMemory");
  }
}

Buffer::Buffer(Context& context, uint64_t size, BufferKind kind, std::string name)
    : device_(context.device()), memory_props_(&context.memory_properties()), size_(size), kind_(kind),
      name_(std::move(name)) {
  if (size == 0) throw Error("buffer " + name_ + ": size 0");
  const VkBufferUsageFlags usage =
      kind == BufferKind::Constants
          ? VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
          // Texel usage: a pass may read a buffer through a uniform texel
          // buffer view (one gathered fetch per texel on lavapipe).
          : VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
                VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  try {
    buffer_ = make_buffer(device_, size, usage);
    VkMemoryPropertyFlags flags = 0;
    bool direct = false;
    switch (kind) {
      case BufferKind::Storage:
        allocate(buffer_, kDeviceLocal, 0, memory_, flags);
        break;
      case BufferKind::Constants:
        allocate(buffer_, kHostVisible, kDeviceLocal | kHostCoherent, memory_, flags);
        direct = true;
        break;
      case BufferKind::StorageUpload:
      case BufferKind::StorageDownload: {
        const VkMemoryPropertyFlags want =
            kDeviceLocal | kHostVisible | (kind == BufferKind::StorageDownload ? kHostCached : 0);
        VkMemoryRequirements req{};
        vkGetBufferMemoryRequirements(device_, buffer_, &req);
        if (!context.force_staging() && find_memory_type(*memory_props_, req.memoryTypeBits, want, kHostCoherent) >= 0) {
          try {
            allocate(buffer_, want, kHostCoherent, memory_, flags);
            direct = true;
          } catch (const VulkanError& e) {
            if (!is_out_of_memory(e.result())) throw;
            // A small BAR heap: fall back to device memory plus staging below.
            vkDestroyBuffer(device_, buffer_, nullptr);
            buffer_ = make_buffer(device_, size, usage);
          }
        }
        if (!direct) {
          allocate(buffer_, kDeviceLocal, 0, memory_, flags);
          staging_ = make_buffer(device_, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT);
          VkMemoryPropertyFlags staging_flags = 0;
          const VkMemoryPropertyFlags preferred =
              kind == BufferKind::StorageDownload ? (kHostCached | kHostCoherent) : kHostCoherent;
          allocate(staging_, kHostVisible, preferred, staging_memory_, staging_flags);
          void* p = nullptr;
          check(vkMapMemory(device_, staging_memory_, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
          mapped_ = static_cast<uint8_t*>(p);
          coherent_ = (staging_flags & kHostCoherent) != 0;
        }
        break;
      }
    }
    if (direct) {
      void* p = nullptr;
      check(vkMapMemory(device_, memory_, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
      mapped_ = static_cast<uint8_t*>(p);
      coherent_ = (flags & kHostCoherent) != 0;
    }
  } catch (...) {
    release();
    throw;
  }
}

Buffer::~Buffer() { release(); }

Buffer::Buffer(Buffer&& other) noexcept { *this = std::move(other); }

Buffer& Buffer::operator=(Buffer&& other) noexcept {
  if (this != &other) {
    release();
    device_ = other.device_;
    memory_props_ = other.memory_props_;
    size_ = other.size_;
    kind_ = other.kind_;
    name_ = std::move(other.name_);
    buffer_ = std::exchange(other.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
    staging_ = std::exchange(other.staging_, VK_NULL_HANDLE);
    staging_memory_ = std::exchange(other.staging_memory_, VK_NULL_HANDLE);
    mapped_ = std::exchange(other.mapped_, nullptr);
    coherent_ = other.coherent_;
    other.size_ = 0;
  }
  return *this;
}

void Buffer::release() noexcept {
  if (!device_) return;
  // Freeing memory unmaps it implicitly.
  if (staging_) vkDestroyBuffer(device_, staging_, nullptr);
  if (staging_memory_) vkFreeMemory(device_, staging_memory_, nullptr);
  if (buffer_) vkDestroyBuffer(device_, buffer_, nullptr);
  if (memory_) vkFreeMemory(device_, memory_, nullptr);
  staging_ = buffer_ = VK_NULL_HANDLE;
  staging_memory_ = memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
}

void Buffer::write(std::span<const uint8_t> bytes, uint64_t offset) {
  write_with(bytes.size(), [&](uint8_t* dst) { std::memcpy(dst, bytes.data(), bytes.size()); }, offset);
}

void Buffer::write_with(uint64_t bytes, const std::function<void(uint8_t*)>& fill, uint64_t offset) {
  if (kind_ != BufferKind::StorageUpload && kind_ != BufferKind::Constants)
    throw Error("buffer " + name_ + " is not host-writable");
  if (offset > size_ || bytes > size_ - offset) throw Error("write past the end of buffer " + name_);
  if (bytes == 0) return;
  fill(mapped_ + offset);
  if (!coherent_) {
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
    range.memory = staged() ? staging_memory_ : memory_;
    range.offset = 0;
    range.size = VK_WHOLE_SIZE;
    check(vkFlushMappedMemoryRanges(device_, 1, &range), "vkFlushMappedMemoryRanges");
  }
}

void Buffer::read(std::span<uint8_t> bytes, uint64_t offset) const {
  read_with(bytes.size(), [&](const uint8_t* src) { std::memcpy(bytes.data(), src, bytes.size()); }, offset);
}

void Buffer::read_with(uint64_t bytes, const std::function<void(const uint8_t*)>& consume, uint64_t offset) const {
  if (kind_ != BufferKind::StorageDownload) throw Error("buffer " + name_ + " is not host-readable");
  if (offset > size_ || bytes > size_ - offset) throw Error("read past the end of buffer " + name_);
  if (bytes == 0) return;
  if (!coherent_) {
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
    range.memory = staged() ? staging_memory_ : memory_;
    range.offset = 0;
    range.size = VK_WHOLE_SIZE;
    check(vkInvalidateMappedMemoryRanges(device_, 1, &range), "vkInvalidateMappedMemoryRanges");
  }
  consume(mapped_ + offset);
}

void Buffer::record_upload(VkCommandBuffer cmd, uint64_t bytes) const {
  if (!staged() || bytes == 0) return;
  VkBufferCopy region{0, 0, bytes};
  vkCmdCopyBuffer(cmd, staging_, buffer_, 1, &region);
}

void Buffer::record_download(VkCommandBuffer cmd, uint64_t bytes) const {
  if (!staged() || bytes == 0) return;
  VkBufferCopy region{0, 0, bytes};
  vkCmdCopyBuffer(cmd, buffer_, staging_, 1, &region);
}

void Buffer::record_readback(VkCommandBuffer cmd, uint64_t bytes, VkPipelineStageFlags stage,
                             VkAccessFlags access) const {
  if (!staged()) {
    memory_barrier(cmd, stage, access, VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
    return;
  }
  memory_barrier(cmd, stage, access, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
  record_download(cmd, bytes);
  memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                 VK_ACCESS_HOST_READ_BIT);
}

}  // namespace dn::gpu
