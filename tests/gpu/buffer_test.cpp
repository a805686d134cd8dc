#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/error.hpp"
#include "gpu/timestamps.hpp"
#include "gpu_test_env.hpp"

namespace dn {
namespace {

class BufferTest : public test::GpuTest {};

std::vector<uint8_t> random_bytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> out(n);
  for (auto& b : out) b = static_cast<uint8_t>(rng());
  return out;
}

// Upload buffer -> device copy -> download buffer, for sizes around word and page boundaries.
// Runs on the direct-mapped context and on the one forced through staging buffers.
TEST_F(BufferTest, UploadCopyDownloadRoundTrip) {
  for (gpu::Context* c : {&test::context(), &test::staging_context()}) {
  for (uint64_t size : {uint64_t{4}, uint64_t{12}, uint64_t{1000}, uint64_t{4096}, uint64_t{(1 << 20) + 4}}) {
    SCOPED_TRACE(testing::Message() << size << (c->force_staging() ? " staged" : " direct"));
    gpu::Context& ctx = *c;
    gpu::Buffer in(ctx, size, gpu::BufferKind::StorageUpload, "in");
    gpu::Buffer mid(ctx, size, gpu::BufferKind::Storage, "mid");
    gpu::Buffer out(ctx, size, gpu::BufferKind::StorageDownload, "out");
    EXPECT_EQ(in.size(), size);
    const auto bytes = random_bytes(size, static_cast<uint32_t>(size));
    in.write(bytes);

    gpu::CommandStream stream(ctx);
    VkCommandBuffer cmd = stream.begin();
    in.record_upload(cmd, size);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    VkBufferCopy region{0, 0, size};
    vkCmdCopyBuffer(cmd, in.handle(), mid.handle(), 1, &region);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    vkCmdCopyBuffer(cmd, mid.handle(), out.handle(), 1, &region);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    out.record_download(cmd, size);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
    stream.submit_and_wait();

    std::vector<uint8_t> back(size);
    out.read(back);
    EXPECT_EQ(back, bytes);
    if (c->force_staging()) {
      EXPECT_TRUE(in.staged());
      EXPECT_TRUE(out.staged());
    }
  }
  }
  expect_no_messages(test::staging_context());
}

TEST_F(BufferTest, LavapipeMapsDeviceMemoryDirectly) {
  if (ctx().info().host_visible_device_memory == false) GTEST_SKIP() << "device has no host-visible device memory";
  gpu::Buffer in(ctx(), 64, gpu::BufferKind::StorageUpload, "in");
  EXPECT_FALSE(in.staged());
}

TEST_F(BufferTest, RejectsWrongDirectionAndOverflow) {
  gpu::Buffer in(ctx(), 16, gpu::BufferKind::StorageUpload, "in");
  gpu::Buffer out(ctx(), 16, gpu::BufferKind::StorageDownload, "out");
  std::vector<uint8_t> bytes(17);
  EXPECT_THROW(in.write(bytes), gpu::Error);
  EXPECT_THROW(in.write(std::span(bytes).first(8), 12), gpu::Error);
  EXPECT_THROW(out.write(std::span(bytes).first(4)), gpu::Error);
  EXPECT_THROW(in.read(std::span(bytes).first(4)), gpu::Error);
  EXPECT_THROW(gpu::Buffer(ctx(), 0, gpu::BufferKind::Storage, "empty"), gpu::Error);
}

TEST_F(BufferTest, MoveTransfersOwnership) {
  gpu::Buffer a(ctx(), 64, gpu::BufferKind::StorageUpload, "a");
  const VkBuffer handle = a.handle();
  gpu::Buffer b(std::move(a));
  EXPECT_EQ(b.handle(), handle);
  EXPECT_EQ(a.handle(), VK_NULL_HANDLE);  // NOLINT(bugprone-use-after-move)
  gpu::Buffer c;
  c = std::move(b);
  EXPECT_EQ(c.handle(), handle);
  EXPECT_EQ(c.size(), 64u);
}

TEST(MemoryTypes, PrefersMostPreferredFlagsAmongAllowed) {
  VkPhysicalDeviceMemoryProperties props{};
  props.memoryTypeCount = 4;
  props.memoryTypes[0].propertyFlags = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  props.memoryTypes[1].propertyFlags = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  props.memoryTypes[2].propertyFlags = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT |
                                       VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
  props.memoryTypes[3].propertyFlags = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
  EXPECT_EQ(gpu::find_memory_type(props, 0xf, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0), 0);
  EXPECT_EQ(gpu::find_memory_type(props, 0xf, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, VK_MEMORY_PROPERTY_HOST_CACHED_BIT), 2);
  EXPECT_EQ(gpu::find_memory_type(props, 0xb, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, VK_MEMORY_PROPERTY_HOST_CACHED_BIT), 1);
  EXPECT_EQ(gpu::find_memory_type(props, 0xf,
                                  VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, 0), 3);
  EXPECT_EQ(gpu::find_memory_type(props, 0x7,
                                  VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, 0), -1);
}

TEST_F(BufferTest, TimestampsMeasureNonNegativeIntervals) {
  gpu::TimestampPool pool(ctx(), 3);
  ASSERT_TRUE(pool.supported());
  gpu::Buffer a(ctx(), 1 << 22, gpu::BufferKind::Storage, "a");
  gpu::Buffer b(ctx(), 1 << 22, gpu::BufferKind::Storage, "b");
  gpu::CommandStream stream(ctx());
  VkCommandBuffer cmd = stream.begin();
  pool.reset(cmd);
  pool.write(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0);
  vkCmdFillBuffer(cmd, a.handle(), 0, VK_WHOLE_SIZE, 0x3f800000u);
  pool.write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 1);
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
  VkBufferCopy region{0, 0, 1 << 22};
  vkCmdCopyBuffer(cmd, a.handle(), b.handle(), 1, &region);
  pool.write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 2);
  stream.submit_and_wait();
  const auto ms = pool.read_intervals_ms(3);
  ASSERT_EQ(ms.size(), 2u);
  for (double v : ms) {
    EXPECT_GE(v, 0.0);
    EXPECT_LT(v, 10000.0);
  }
}

}  // namespace
}  // namespace dn
