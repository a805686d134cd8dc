// A VkPipelineCache kept on disk between server runs, so a restarted server
// (or a new session's first frame) does not recompile what a previous run
// compiled. The file is one device's cache: its name carries the vendor,
// device and driver cache UUID, and a file whose header does not match this
// device is ignored (never handed to the driver). Saved atomically: written to
// a temporary file in the same directory, then renamed over the old one.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <mutex>
#include <string>

namespace dn::gpu {

class PipelineCache {
 public:
  // directory: where the cache file lives ("" = in memory only). The caller
  // has checked that the directory is safe to use (server/cache_dir.hpp).
  PipelineCache(VkDevice device, const VkPhysicalDeviceProperties& properties, std::string directory);
  ~PipelineCache();
  PipelineCache(const PipelineCache&) = delete;
  PipelineCache& operator=(const PipelineCache&) = delete;

  VkPipelineCache handle() const { return cache_; }
  // The file ("" without a directory).
  const std::string& path() const { return path_; }
  // Bytes read from disk at start-up (0: no file, or it did not match this device).
  uint64_t loaded_bytes() const { return loaded_bytes_; }
  // Why the file on disk was not used ("" when it was, or there was none).
  const std::string& load_note() const { return load_note_; }

  // Writes the cache to its file; returns the bytes written, 0 without a
  // directory. Throws std::runtime_error naming the path on failure.
  uint64_t save();

  // The file name this device's cache gets inside a directory.
  static std::string file_name(const VkPhysicalDeviceProperties& properties);

 private:
  VkDevice device_;
  VkPhysicalDeviceProperties properties_;
  std::string path_;
  VkPipelineCache cache_ = VK_NULL_HANDLE;
  uint64_t loaded_bytes_ = 0;
  std::string load_note_;
  std::mutex save_mutex_;
};

}  // namespace dn::gpu
