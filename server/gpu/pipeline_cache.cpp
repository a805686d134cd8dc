#include "gpu/pipeline_cache.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "gpu/error.hpp"

namespace dn::gpu {
namespace {

// Larger files are not ours to load (a real cache is a few MiB at most).
constexpr uint64_t kMaxCacheFileBytes = 256ull << 20;

std::string hex(const uint8_t* bytes, size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    out += digits[bytes[i] >> 4];
    out += digits[bytes[i] & 15];
  }
  return out;
}

// Reads a regular file, refusing symlinks and anything too large.
bool read_file(const std::string& path, std::vector<uint8_t>& out, std::string& note) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    if (errno != ENOENT) note = "cannot open " + path + ": " + std::strerror(errno);
    return false;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || static_cast<uint64_t>(st.st_size) > kMaxCacheFileBytes) {
    note = path + " is not a regular file of at most " + std::to_string(kMaxCacheFileBytes) + " bytes";
    ::close(fd);
    return false;
  }
  out.resize(static_cast<size_t>(st.st_size));
  size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::read(fd, out.data() + done, out.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  out.resize(done);
  return true;
}

// The header every VkPipelineCache blob starts with (Vulkan spec,
// VkPipelineCacheHeaderVersionOne): length, version, vendor, device, UUID.
bool header_matches(const std::vector<uint8_t>& data, const VkPhysicalDeviceProperties& p, std::string& note) {
  VkPipelineCacheHeaderVersionOne h{};
  if (data.size() < sizeof h) {
    note = "cache file shorter than its header";
    return false;
  }
  std::memcpy(&h, data.data(), sizeof h);
  // The version as the file's 32 bits: any value may be there, and an enum
  // holding one it does not name is undefined behaviour (UBSan, scripts/sanitize.sh).
  uint32_t version = 0;
  std::memcpy(&version, data.data() + offsetof(VkPipelineCacheHeaderVersionOne, headerVersion), sizeof version);
  if (h.headerSize < sizeof h || version != VK_PIPELINE_CACHE_HEADER_VERSION_ONE || h.vendorID != p.vendorID ||
      h.deviceID != p.deviceID || std::memcmp(h.pipelineCacheUUID, p.pipelineCacheUUID, VK_UUID_SIZE) != 0) {
    note = "cache file was written by another device or driver";
    return false;
  }
  return true;
}

}  // namespace

std::string PipelineCache::file_name(const VkPhysicalDeviceProperties& p) {
  char ids[32];
  std::snprintf(ids, sizeof ids, "%04x-%04x-", p.vendorID, p.deviceID);
  return std::string("pipelines-") + ids + hex(p.pipelineCacheUUID, VK_UUID_SIZE) + ".bin";
}

PipelineCache::PipelineCache(VkDevice device, const VkPhysicalDeviceProperties& properties, std::string directory)
    : device_(device), properties_(properties) {
  std::vector<uint8_t> initial;
  if (!directory.empty()) {
    path_ = directory + "/" + file_name(properties);
    if (read_file(path_, initial, load_note_) && !header_matches(initial, properties, load_note_)) initial.clear();
  }
  VkPipelineCacheCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
  info.initialDataSize = initial.size();
  info.pInitialData = initial.empty() ? nullptr : initial.data();
  VkResult r = vkCreatePipelineCache(device_, &info, nullptr, &cache_);
  if (r != VK_SUCCESS && !initial.empty()) {
    // The driver refused the blob despite a matching header: start empty.
    load_note_ = "driver refused the cache file";
    info.initialDataSize = 0;
    info.pInitialData = nullptr;
    initial.clear();
    r = vkCreatePipelineCache(device_, &info, nullptr, &cache_);
  }
  check(r, "vkCreatePipelineCache");
  loaded_bytes_ = initial.size();
}

PipelineCache::~PipelineCache() {
  if (cache_) vkDestroyPipelineCache(device_, cache_, nullptr);
}

uint64_t PipelineCache::save() {
  if (path_.empty()) return 0;
  std::lock_guard lock(save_mutex_);
  size_t size = 0;
  check(vkGetPipelineCacheData(device_, cache_, &size, nullptr), "vkGetPipelineCacheData");
  std::vector<uint8_t> data(size);
  VkResult r = vkGetPipelineCacheData(device_, cache_, &size, data.data());
  if (r != VK_SUCCESS && r != VK_INCOMPLETE) check(r, "vkGetPipelineCacheData");
  data.resize(size);

  const std::string tmp = path_ + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) throw std::runtime_error("pipeline cache: cannot create " + tmp + ": " + std::strerror(errno));
  size_t done = 0;
  bool ok = true;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ok = false;
      break;
    }
    done += static_cast<size_t>(n);
  }
  const int saved_errno = errno;
  ok = ::close(fd) == 0 && ok;
  if (!ok || ::rename(tmp.c_str(), path_.c_str()) != 0) {
    const std::string reason = std::strerror(ok ? errno : saved_errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error("pipeline cache: cannot write " + path_ + ": " + reason);
  }
  return data.size();
}

}  // namespace dn::gpu
