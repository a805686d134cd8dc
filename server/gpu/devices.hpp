// Physical devices: what `dnserver --list-devices` prints and how a device
// selector string picks one.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace dn::gpu {

struct DeviceInfo {
  uint32_t index = 0;        // position in vkEnumeratePhysicalDevices order
  std::string name;          // VkPhysicalDeviceProperties::deviceName
  std::string type;          // "discrete", "integrated", "virtual", "cpu" or "other"
  std::string api_version;   // "1.3.230"
  std::string driver;        // driver name and info when the driver reports them
  uint32_t vendor_id = 0;
  uint32_t device_id = 0;
  uint64_t device_local_bytes = 0;        // sum of DEVICE_LOCAL heaps
  uint64_t max_storage_buffer_range = 0;  // largest storage-buffer binding
  bool host_visible_device_memory = false;  // DEVICE_LOCAL|HOST_VISIBLE type (UMA, lavapipe, ReBAR)
  bool suitable = false;     // Vulkan >= 1.2 and a compute queue
  std::string unsuitable_reason;
};

// Describes one physical device (index = its enumeration position).
DeviceInfo describe_device(VkPhysicalDevice device, uint32_t index);

// Picks a device for `selector`:
//  - empty: the first suitable discrete GPU, else integrated, else virtual,
//    else CPU (lavapipe), else any other suitable device;
//  - all digits: that index (must be suitable);
//  - otherwise: the first suitable device whose name contains the selector,
//    case-insensitively.
// Returns the position in `devices`; throws gpu::Error naming the candidates
// when nothing matches.
size_t select_device(const std::vector<DeviceInfo>& devices, std::string_view selector);

// One line per device, for logs and --list-devices.
std::string format_device(const DeviceInfo& info);

}  // namespace dn::gpu
