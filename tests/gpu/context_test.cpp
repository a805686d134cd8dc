#include <gtest/gtest.h>

#include "gpu/error.hpp"
#include "gpu/limits.hpp"
#include "gpu_test_env.hpp"

namespace dn {
namespace {

using gpu::DeviceInfo;

DeviceInfo fake(uint32_t index, std::string name, std::string type, bool suitable = true) {
  DeviceInfo d;
  d.index = index;
  d.name = std::move(name);
  d.type = std::move(type);
  d.suitable = suitable;
  if (!suitable) d.unsuitable_reason = "Vulkan 1.1.0 < 1.2";
  return d;
}

TEST(DeviceSelection, EmptySelectorPrefersDiscreteThenIntegratedThenCpu) {
  std::vector<DeviceInfo> devices = {fake(0, "llvmpipe (LLVM 15)", "cpu"), fake(1, "Intel UHD 770", "integrated"),
                                     fake(2, "NVIDIA RTX 4080", "discrete")};
  EXPECT_EQ(gpu::select_device(devices, ""), 2u);
  devices.pop_back();
  EXPECT_EQ(gpu::select_device(devices, ""), 1u);
  devices.pop_back();
  EXPECT_EQ(gpu::select_device(devices, ""), 0u);
}

TEST(DeviceSelection, SkipsUnsuitableDevices) {
  std::vector<DeviceInfo> devices = {fake(0, "Old GPU", "discrete", false), fake(1, "llvmpipe", "cpu")};
  EXPECT_EQ(gpu::select_device(devices, ""), 1u);
  EXPECT_THROW(gpu::select_device(devices, "old"), gpu::Error);
  try {
    gpu::select_device(devices, "0");
    FAIL() << "an unsuitable device was selected by index";
  } catch (const gpu::Error& e) {
    EXPECT_NE(std::string(e.what()).find("unsuitable"), std::string::npos) << e.what();
  }
}

TEST(DeviceSelection, IndexAndCaseInsensitiveSubstring) {
  std::vector<DeviceInfo> devices = {fake(0, "llvmpipe (LLVM 15)", "cpu"), fake(1, "NVIDIA RTX 4080", "discrete")};
  EXPECT_EQ(gpu::select_device(devices, "0"), 0u);
  EXPECT_EQ(gpu::select_device(devices, "1"), 1u);
  EXPECT_EQ(gpu::select_device(devices, "rtx"), 1u);
  EXPECT_EQ(gpu::select_device(devices, "LLVMPIPE"), 0u);
}

TEST(DeviceSelection, NoMatchNamesTheCandidates) {
  std::vector<DeviceInfo> devices = {fake(0, "llvmpipe (LLVM 15)", "cpu")};
  try {
    gpu::select_device(devices, "radeon");
    FAIL() << "no exception";
  } catch (const gpu::Error& e) {
    EXPECT_NE(std::string(e.what()).find("llvmpipe"), std::string::npos) << e.what();
  }
  EXPECT_THROW(gpu::select_device(devices, "7"), gpu::Error);
  EXPECT_THROW(gpu::select_device({}, ""), gpu::Error);
}

TEST(VulkanErrors, NamesTheResult) {
  EXPECT_EQ(gpu::result_name(VK_ERROR_DEVICE_LOST), "VK_ERROR_DEVICE_LOST");
  EXPECT_EQ(gpu::result_name(static_cast<VkResult>(-12345)), "VK_RESULT(-12345)");
  try {
    gpu::check(VK_ERROR_OUT_OF_DEVICE_MEMORY, "vkAllocateMemory");
    FAIL();
  } catch (const gpu::VulkanError& e) {
    EXPECT_EQ(e.result(), VK_ERROR_OUT_OF_DEVICE_MEMORY);
    EXPECT_STREQ(e.what(), "vkAllocateMemory: VK_ERROR_OUT_OF_DEVICE_MEMORY");
  }
}

TEST(ListDevices, FindsLavapipe) {
  const auto devices = gpu::Context::list_devices();
  ASSERT_FALSE(devices.empty());
  bool found = false;
  for (const auto& d : devices) {
    EXPECT_FALSE(gpu::format_device(d).empty());
    if (d.name.find("llvmpipe") == std::string::npos) continue;
    found = true;
    EXPECT_EQ(d.type, "cpu");
    EXPECT_TRUE(d.suitable) << d.unsuitable_reason;
    EXPECT_GE(d.max_storage_buffer_range, uint64_t{1} << 27);
    EXPECT_TRUE(d.host_visible_device_memory);
    EXPECT_GT(d.device_local_bytes, 0u);
  }
  EXPECT_TRUE(found) << "lavapipe (mesa-vulkan-drivers) is not installed";
}

class ContextTest : public test::GpuTest {};

TEST_F(ContextTest, CreatesOnLavapipeAndPublishesLimits) {
  gpu::Context& c = ctx();
  EXPECT_NE(c.device(), VK_NULL_HANDLE);
  EXPECT_FALSE(c.name().empty());
  if (test::test_device_selector() == "llvmpipe") {
    EXPECT_NE(c.name().find("llvmpipe"), std::string::npos);
    EXPECT_EQ(c.limits().max_storage_buffer_range, uint64_t{128} << 20);
  }
  EXPECT_GT(c.timestamp_valid_bits(), 0u);
  EXPECT_GT(c.timestamp_period_ns(), 0.0);
  EXPECT_EQ(gpu::current_device_limits().max_storage_buffer_range, c.limits().max_storage_buffer_range);
  EXPECT_EQ(c.validation_enabled(), gpu::Context::validation_layer_available());
  EXPECT_FALSE(c.lost());
}

TEST(ContextErrors, UnknownSelectorThrows) {
  gpu::ContextOptions options;
  options.device = "no-such-device-xyz";
  EXPECT_THROW(gpu::Context{options}, gpu::Error);
}

TEST(ContextErrors, SecondContextWorksAlongsideTheFirst) {
  test::context();
  gpu::ContextOptions options;
  options.device = test::test_device_selector();
  gpu::Context second(options);
  EXPECT_EQ(second.name(), test::context().name());
}

}  // namespace
}  // namespace dn

namespace dn {
namespace {

// The messenger really counts: a command buffer that dispatches with no
// pipeline bound is reported (recorded only, never submitted).
TEST(Validation, MessengerCountsLayerMessages) {
  if (!gpu::Context::validation_layer_available()) GTEST_SKIP() << "VK_LAYER_KHRONOS_validation not installed";
  gpu::ContextOptions options;
  options.device = test::test_device_selector();
  options.validation = true;
  options.print_validation_messages = false;
  gpu::Context c(options);
  ASSERT_TRUE(c.validation_enabled());
  EXPECT_EQ(c.validation_message_count(), 0u);

  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.queueFamilyIndex = c.queue_family();
  VkCommandPool pool;
  ASSERT_EQ(vkCreateCommandPool(c.device(), &pool_info, nullptr, &pool), VK_SUCCESS);
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = pool;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cmd;
  ASSERT_EQ(vkAllocateCommandBuffers(c.device(), &alloc, &cmd), VK_SUCCESS);
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  vkBeginCommandBuffer(cmd, &begin);
  vkCmdDispatch(cmd, 1, 1, 1);
  vkEndCommandBuffer(cmd);
  vkDestroyCommandPool(c.device(), pool, nullptr);

  EXPECT_GT(c.validation_message_count(), 0u);
  ASSERT_FALSE(c.validation_messages().empty());
  EXPECT_NE(c.validation_messages().back().find("error"), std::string::npos) << c.validation_messages().back();
}

TEST(Validation, EnvironmentVariableTurnsItOn) {
  if (!gpu::Context::validation_layer_available()) GTEST_SKIP() << "VK_LAYER_KHRONOS_validation not installed";
  setenv("DN_VALIDATION", "1", 1);
  gpu::ContextOptions options;
  options.device = test::test_device_selector();
  gpu::Context with_env(options);
  unsetenv("DN_VALIDATION");
  EXPECT_TRUE(with_env.validation_enabled());
  gpu::Context without(options);
  EXPECT_FALSE(without.validation_enabled());
}

}  // namespace
}  // namespace dn
