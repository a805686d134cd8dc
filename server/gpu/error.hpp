// Exceptions of the device layer. Every failing Vulkan call becomes a
// VulkanError that names the call and the VkResult (e.g.
// "vkAllocateMemory: VK_ERROR_OUT_OF_DEVICE_MEMORY").
#pragma once

#include <vulkan/vulkan.h>

#include <stdexcept>
#include <string>

namespace dn::gpu {

// Any failure of the device layer (no device, missing shader, bad argument).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class VulkanError : public Error {
 public:
  VulkanError(VkResult result, const std::string& call);
  VkResult result() const { return result_; }

 private:
  VkResult result_;
};

// "VK_ERROR_DEVICE_LOST" etc.; "VK_RESULT(<n>)" for values it does not know.
std::string result_name(VkResult result);

// Throws VulkanError when result is not VK_SUCCESS.
inline void check(VkResult result, const char* call) {
  if (result != VK_SUCCESS) throw VulkanError(result, call);
}

}  // namespace dn::gpu
