#include "gpu/devices.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <sstream>

#include "gpu/error.hpp"

namespace dn::gpu {
namespace {

const char* type_name(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

int type_rank(const std::string& type) {
  if (type == "discrete") return 0;
  if (type == "integrated") return 1;
  if (type == "virtual") return 2;
  if (type == "cpu") return 3;
  return 4;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string version_string(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

std::string candidates(const std::vector<DeviceInfo>& devices) {
  std::string out;
  for (const auto& d : devices) {
    if (!out.empty()) out += ", ";
    out += std::to_string(d.index) + ": " + d.name + (d.suitable ? "" : " (unsuitable: " + d.unsuitable_reason + ")");
  }
  return out.empty() ? "none" : out;
}

}  // namespace

DeviceInfo describe_device(VkPhysicalDevice device, uint32_t index) {
  DeviceInfo info;
  info.index = index;

  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  VkPhysicalDeviceProperties props{};
  vkGetPhysicalDeviceProperties(device, &props);
  const bool is_12 = props.apiVersion >= VK_API_VERSION_1_2;
  if (is_12) {
    props2.pNext = &driver;
    vkGetPhysicalDeviceProperties2(device, &props2);
  }

  info.name = props.deviceName;
  info.type = type_name(props.deviceType);
  info.api_version = version_string(props.apiVersion);
  info.vendor_id = props.vendorID;
  info.device_id = props.deviceID;
  info.max_storage_buffer_range = props.limits.maxStorageBufferRange;
  if (is_12) {
    info.driver = driver.driverName;
    if (driver.driverInfo[0] != '\0') info.driver += std::string(" ") + driver.driverInfo;
  }

  VkPhysicalDeviceMemoryProperties mem{};
  vkGetPhysicalDeviceMemoryProperties(device, &mem);
  for (uint32_t h = 0; h < mem.memoryHeapCount; ++h)
    if (mem.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) info.device_local_bytes += mem.memoryHeaps[h].size;
  const VkMemoryPropertyFlags both = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
  for (uint32_t t = 0; t < mem.memoryTypeCount; ++t)
    if ((mem.memoryTypes[t].propertyFlags & both) == both) info.host_visible_device_memory = true;

  uint32_t family_count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(device, &family_count, nullptr);
  std::vector<VkQueueFamilyProperties> families(family_count);
  vkGetPhysicalDeviceQueueFamilyProperties(device, &family_count, families.data());
  const bool has_compute = std::any_of(families.begin(), families.end(), [](const VkQueueFamilyProperties& f) {
    return (f.queueFlags & VK_QUEUE_COMPUTE_BIT) && f.queueCount > 0;
  });

  if (!is_12) {
    info.unsuitable_reason = "Vulkan " + info.api_version + " < 1.2";
  } else if (!has_compute) {
    info.unsuitable_reason = "no compute queue";
  } else {
    info.suitable = true;
  }
  return info;
}

size_t select_device(const std::vector<DeviceInfo>& devices, std::string_view selector) {
  if (selector.empty()) {
    size_t best = devices.size();
    for (size_t i = 0; i < devices.size(); ++i) {
      if (!devices[i].suitable) continue;
      if (best == devices.size() || type_rank(devices[i].type) < type_rank(devices[best].type)) best = i;
    }
    if (best == devices.size()) throw Error("no suitable Vulkan device (need 1.2 and a compute queue); found: " + candidates(devices));
    return best;
  }
  const bool numeric = std::all_of(selector.begin(), selector.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (numeric && selector.size() < 10) {
    const uint32_t want = static_cast<uint32_t>(std::stoul(std::string(selector)));
    for (size_t i = 0; i < devices.size(); ++i) {
      if (devices[i].index != want) continue;
      if (!devices[i].suitable)
        throw Error("device " + std::to_string(want) + " (" + devices[i].name + ") is unsuitable: " + devices[i].unsuitable_reason);
      return i;
    }
    throw Error("no Vulkan device with index " + std::string(selector) + "; found: " + candidates(devices));
  }
  const std::string needle = lower(selector);
  for (size_t i = 0; i < devices.size(); ++i)
    if (devices[i].suitable && lower(devices[i].name).find(needle) != std::string::npos) return i;
  throw Error("no suitable Vulkan device matches \"" + std::string(selector) + "\"; found: " + candidates(devices));
}

std::string format_device(const DeviceInfo& info) {
  std::ostringstream out;
  out << info.index << ": " << info.name << " [" << info.type << ", Vulkan " << info.api_version;
  if (!info.driver.empty()) out << ", " << info.driver;
  out << "] " << (info.device_local_bytes >> 20) << " MiB device-local, max storage binding "
      << (info.max_storage_buffer_range >> 20) << " MiB" << (info.host_visible_device_memory ? ", host-visible device memory" : "");
  if (!info.suitable) out << " (unsuitable: " << info.unsuitable_reason << ")";
  return out.str();
}

}  // namespace dn::gpu
