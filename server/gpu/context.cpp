#include "gpu/context.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "gpu/compute.hpp"
#include "gpu/error.hpp"
#include "gpu/pipeline_cache.hpp"

namespace dn::gpu {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
constexpr size_t kRecentMessages = 64;

bool env_validation() {
  const char* v = std::getenv("DN_VALIDATION");
  return v != nullptr && std::strcmp(v, "0") != 0 && v[0] != '\0';
}

bool has_instance_extension(const char* name) {
  uint32_t count = 0;
  if (vkEnumerateInstanceExtensionProperties(nullptr, &count, nullptr) != VK_SUCCESS) return false;
  std::vector<VkExtensionProperties> exts(count);
  if (vkEnumerateInstanceExtensionProperties(nullptr, &count, exts.data()) != VK_SUCCESS) return false;
  for (const auto& e : exts)
    if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

VKAPI_ATTR VkBool32 VKAPI_CALL on_debug_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                VkDebugUtilsMessageTypeFlagsEXT,
                                                const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* state = static_cast<Context::ValidationState*>(user);
  const char* level = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) ? "error" : "warning";
  std::string text = std::string("[vulkan ") + level + "] " + (data && data->pMessage ? data->pMessage : "(no message)");
  state->count.fetch_add(1);
  {
    std::lock_guard lock(state->mutex);
    state->recent.push_back(text);
    if (state->recent.size() > kRecentMessages) state->recent.pop_front();
  }
  if (state->print) std::fprintf(stderr, "%s\n", text.c_str());
  return VK_FALSE;
}

VkDebugUtilsMessengerCreateInfoEXT messenger_info(Context::ValidationState* state) {
  VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  info.pfnUserCallback = on_debug_message;
  info.pUserData = state;
  return info;
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance instance) {
  uint32_t count = 0;
  check(vkEnumeratePhysicalDevices(instance, &count, nullptr), "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> devices(count);
  VkResult r = vkEnumeratePhysicalDevices(instance, &count, devices.data());
  if (r != VK_INCOMPLETE) check(r, "vkEnumeratePhysicalDevices");
  devices.resize(count);
  return devices;
}

VkInstance create_plain_instance() {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "dnserver";
  app.pEngineName = "dn";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  check(vkCreateInstance(&info, nullptr, &instance), "vkCreateInstance");
  return instance;
}

}  // namespace

bool Context::validation_layer_available() {
  uint32_t count = 0;
  if (vkEnumerateInstanceLayerProperties(&count, nullptr) != VK_SUCCESS) return false;
  std::vector<VkLayerProperties> layers(count);
  if (vkEnumerateInstanceLayerProperties(&count, layers.data()) != VK_SUCCESS) return false;
  for (const auto& l : layers)
    if (std::strcmp(l.layerName, kValidationLayer) == 0) return true;
  return false;
}

std::vector<DeviceInfo> Context::list_devices() {
  VkInstance instance = create_plain_instance();
  std::vector<DeviceInfo> out;
  try {
    auto devices = physical_devices(instance);
    for (uint32_t i = 0; i < devices.size(); ++i) out.push_back(describe_device(devices[i], i));
  } catch (...) {
    vkDestroyInstance(instance, nullptr);
    throw;
  }
  vkDestroyInstance(instance, nullptr);
  return out;
}

Context::Context(const ContextOptions& options)
    : options_(options), validation_(std::make_unique<ValidationState>()), force_staging_(options.force_staging) {
  validation_->print = options.print_validation_messages;
  bool validation = options.validation || env_validation();
  if (validation && !validation_layer_available()) {
    std::fprintf(stderr, "dn::gpu: validation requested but %s is not installed; continuing without it\n",
                 kValidationLayer);
    validation = false;
  }
  try {
    create_instance(validation, options.synchronization_validation);

    auto devices = physical_devices(instance_);
    std::vector<DeviceInfo> infos;
    for (uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe_device(devices[i], i));
    const size_t chosen = select_device(infos, options.device);
    physical_ = devices[chosen];
    info_ = infos[chosen];
    create_device();
    pipeline_cache_ = std::make_unique<PipelineCache>(device_, properties_, options.pipeline_cache_dir);
    kernels_ = std::make_unique<KernelCache>(device_, pipeline_cache_->handle());
  } catch (...) {
    kernels_.reset();
    pipeline_cache_.reset();
    if (device_) vkDestroyDevice(device_, nullptr);
    if (messenger_) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
      if (destroy) destroy(instance_, messenger_, nullptr);
    }
    if (instance_) vkDestroyInstance(instance_, nullptr);
    throw;
  }
  publish_device_limits(limits_);
}

void Context::create_instance(bool validation, bool sync_validation) {
  uint32_t loader_version = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&loader_version);
  if (loader_version < VK_API_VERSION_1_2)
    throw Error("the Vulkan loader supports only " + std::to_string(VK_API_VERSION_MAJOR(loader_version)) + "." +
                std::to_string(VK_API_VERSION_MINOR(loader_version)) + "; need 1.2");

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "dnserver";
  app.pEngineName = "dn";
  app.apiVersion = VK_API_VERSION_1_2;

  std::vector<const char*> layers;
  std::vector<const char*> extensions;
  const bool debug_utils = validation && has_instance_extension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (validation) layers.push_back(kValidationLayer);
  if (debug_utils) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);

  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  info.enabledLayerCount = static_cast<uint32_t>(layers.size());
  info.ppEnabledLayerNames = layers.data();
  info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();

  // Chained so that instance creation and destruction are validated too.
  VkDebugUtilsMessengerCreateInfoEXT dbg = messenger_info(validation_.get());
  VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  features.enabledValidationFeatureCount = 1;
  features.pEnabledValidationFeatures = enables;
  if (debug_utils) {
    info.pNext = &dbg;
    if (sync_validation) dbg.pNext = &features;
  }
  check(vkCreateInstance(&info, nullptr, &instance_), "vkCreateInstance");

  if (debug_utils) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (!create) throw VulkanError(VK_ERROR_EXTENSION_NOT_PRESENT, "vkCreateDebugUtilsMessengerEXT");
    VkDebugUtilsMessengerCreateInfoEXT m = messenger_info(validation_.get());
    check(create(instance_, &m, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
  }
}

void Context::create_device() {
  vkGetPhysicalDeviceProperties(physical_, &properties_);
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

  uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &count, families.data());
  // Prefer a family with timestamps; among those a compute family without
  // graphics (dedicated/async compute), else the first compute family.
  int best = -1;
  auto score = [&](uint32_t i) {
    const auto& f = families[i];
    return (f.timestampValidBits > 0 ? 2 : 0) + ((f.queueFlags & VK_QUEUE_GRAPHICS_BIT) ? 0 : 1);
  };
  for (uint32_t i = 0; i < count; ++i) {
    if (!(families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) || families[i].queueCount == 0) continue;
    if (best < 0 || score(i) > score(static_cast<uint32_t>(best))) best = static_cast<int>(i);
  }
  if (best < 0) throw Error("device " + info_.name + " has no compute queue");
  queue_family_ = static_cast<uint32_t>(best);
  timestamp_bits_ = families[queue_family_].timestampValidBits;

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue.queueFamilyIndex = queue_family_;
  queue.queueCount = 1;
  queue.pQueuePriorities = &priority;
  VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  info.queueCreateInfoCount = 1;
  info.pQueueCreateInfos = &queue;
  check(vkCreateDevice(physical_, &info, nullptr, &device_), "vkCreateDevice");
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

  VkPhysicalDeviceMaintenance3Properties m3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
  VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  p2.pNext = &m3;
  vkGetPhysicalDeviceProperties2(physical_, &p2);
  const auto& l = properties_.limits;
  limits_.max_storage_buffer_range = l.maxStorageBufferRange;
  limits_.max_memory_allocation_size = m3.maxMemoryAllocationSize;
  for (int i = 0; i < 3; ++i) limits_.max_compute_work_group_count[i] = l.maxComputeWorkGroupCount[i];
  limits_.max_compute_work_group_invocations = l.maxComputeWorkGroupInvocations;
  limits_.max_texel_buffer_elements = l.maxTexelBufferElements;
}

Context::~Context() {
  if (device_) {
    vkDeviceWaitIdle(device_);  // result ignored: nothing useful to do on loss at teardown
    shared_.clear();  // shared resources (buffers, kernels) before the cache and the device
    kernels_.reset();
    pipeline_cache_.reset();
    vkDestroyDevice(device_, nullptr);
  }
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

std::vector<std::string> Context::validation_messages() const {
  std::lock_guard lock(validation_->mutex);
  return {validation_->recent.begin(), validation_->recent.end()};
}

void Context::submit(VkCommandBuffer command_buffer, VkFence fence) {
  if (lost()) throw VulkanError(VK_ERROR_DEVICE_LOST, "vkQueueSubmit");
  VkSubmitInfo info{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  info.commandBufferCount = 1;
  info.pCommandBuffers = &command_buffer;
  VkResult r;
  {
    std::lock_guard lock(submit_mutex_);
    r = vkQueueSubmit(queue_, 1, &info, fence);
  }
  if (r == VK_ERROR_DEVICE_LOST) mark_lost();
  check(r, "vkQueueSubmit");
}

}  // namespace dn::gpu
