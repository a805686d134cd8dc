// Device buffers and how the host reaches them.
//
// Every storage buffer lives in DEVICE_LOCAL memory. Host access:
//  - Upload buffers map DEVICE_LOCAL|HOST_VISIBLE memory directly when the
//    device has it (lavapipe, integrated GPUs, ReBAR); otherwise, or when
//    that allocation fails (small BAR heap), they get a HOST_VISIBLE staging
//    buffer and record_upload() copies it on the device.
//  - Download buffers map directly only when the memory is also HOST_CACHED
//    (reading uncached write-combined memory is slow); otherwise they read
//    back through a HOST_CACHED staging buffer (record_download()).
//  - Uniform buffers are HOST_VISIBLE (DEVICE_LOCAL preferred), never staged.
// Non-coherent memory is flushed after write() and invalidated before read().
// size() is the requested size (what device-bytes accounting counts); the
// driver may round its allocation up.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <span>
#include <string>

namespace dn::gpu {

class Context;

enum class BufferKind {
  Storage,          // device-only storage buffer
  StorageUpload,    // storage buffer the host writes (input planes)
  StorageDownload,  // storage buffer the host reads (output planes)
  Constants,        // per-frame constants, host-written; a read-only storage buffer in the kernels
                    // (not a uniform buffer: lavapipe inlines uniform values, see shaders/include/frame.glsl)
};

class Buffer {
 public:
  Buffer() = default;
  Buffer(Context& context, uint64_t size, BufferKind kind, std::string name = {});
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  VkBuffer handle() const { return buffer_; }
  uint64_t size() const { return size_; }
  BufferKind kind() const { return kind_; }
  const std::string& name() const { return name_; }
  // Host access goes through a staging buffer (record_upload/record_download needed).
  bool staged() const { return staging_ != VK_NULL_HANDLE; }

  // Copies bytes to offset in the host-visible memory (the buffer itself or
  // its staging buffer). Upload and Uniform buffers only.
  void write(std::span<const uint8_t> bytes, uint64_t offset = 0);
  // The same, but `fill` writes the `bytes` bytes at offset itself (a copy
  // that converts as it goes).
  void write_with(uint64_t bytes, const std::function<void(uint8_t*)>& fill, uint64_t offset = 0);
  // Records the staging -> device copy of [0, bytes) (no-op when not staged).
  void record_upload(VkCommandBuffer cmd, uint64_t bytes) const;
  // Records the device -> staging copy of [0, bytes) (no-op when not staged).
  void record_download(VkCommandBuffer cmd, uint64_t bytes) const;
  // Everything between work that wrote [0, bytes) (in `stage` with `access`)
  // and read() after the submission completes: the barrier, the staging copy
  // when staged, and the barrier to host reads.
  void record_readback(VkCommandBuffer cmd, uint64_t bytes, VkPipelineStageFlags stage, VkAccessFlags access) const;
  // Copies bytes from offset of the host-visible memory. Download buffers only;
  // call after the work (and record_download) has completed.
  void read(std::span<uint8_t> bytes, uint64_t offset = 0) const;
  // The same, but `consume` reads the `bytes` bytes at offset itself.
  void read_with(uint64_t bytes, const std::function<void(const uint8_t*)>& consume, uint64_t offset = 0) const;

 private:
  void release() noexcept;
  void allocate(VkBuffer buffer, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                VkDeviceMemory& memory, VkMemoryPropertyFlags& flags) const;

  VkDevice device_ = VK_NULL_HANDLE;
  const VkPhysicalDeviceMemoryProperties* memory_props_ = nullptr;
  uint64_t size_ = 0;
  BufferKind kind_ = BufferKind::Storage;
  std::string name_;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkBuffer staging_ = VK_NULL_HANDLE;
  VkDeviceMemory staging_memory_ = VK_NULL_HANDLE;
  uint8_t* mapped_ = nullptr;      // host view of the buffer or of its staging buffer
  bool coherent_ = true;           // of the mapped memory
};

// Index of a memory type allowed by type_bits with all `required` flags,
// preferring the most `preferred` flags; -1 if none.
int find_memory_type(const VkPhysicalDeviceMemoryProperties& props, uint32_t type_bits,
                     VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred);

}  // namespace dn::gpu
