// plane.glsl through the plane_probe kernel: fp32 planes of 1, 2 and 3
// components decode exactly on the device, subnormals, infinities and signed
// zeros included. (fp16 planes are widened on the host before they reach the
// device: tests/pipelines/wire_format_test.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "dn/shaders/shaders.hpp"
#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/error.hpp"
#include "gpu_test_env.hpp"

namespace dn {
namespace {

class PlaneIoTest : public test::GpuTest {
 protected:
  // Runs plane_probe on `bytes` (pixels * components elements) and returns the decoded floats.
  std::vector<float> decode(const std::vector<uint8_t>& bytes, uint32_t pixels, uint32_t components) {
    gpu::KernelDesc desc;
    desc.name = "plane_probe";
    desc.spirv = shaders::get("plane_probe");
    desc.storage_buffers = 2;
    desc.spec_constants = {{0, 64}, {1, components}};
    auto kernel = ctx().kernels().get(desc);

    gpu::Buffer uniform(ctx(), 96, gpu::BufferKind::Constants, "frame");
    uint32_t constants[24] = {pixels, 1, pixels, 0};
    uniform.write({reinterpret_cast<const uint8_t*>(constants), sizeof constants});
    gpu::Buffer in(ctx(), (bytes.size() + 3) & ~size_t{3}, gpu::BufferKind::StorageUpload, "plane");
    in.write(bytes);
    const uint64_t out_bytes = uint64_t{pixels} * components * 4;
    gpu::Buffer out(ctx(), out_bytes, gpu::BufferKind::StorageDownload, "decoded");

    gpu::DescriptorPool pool(ctx(), 1, 2);
    const VkBuffer storage[] = {in.handle(), out.handle()};
    VkDescriptorSet set = pool.allocate(*kernel, uniform.handle(), storage);

    gpu::CommandStream stream(ctx());
    VkCommandBuffer cmd = stream.begin();
    in.record_upload(cmd, bytes.size());
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel->pipeline());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel->layout(), 0, 1, &set, 0, nullptr);
    vkCmdDispatch(cmd, (pixels + 63) / 64, 1, 1);
    out.record_readback(cmd, out_bytes, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    stream.submit_and_wait();

    std::vector<float> decoded(uint64_t{pixels} * components);
    out.read({reinterpret_cast<uint8_t*>(decoded.data()), out_bytes});
    return decoded;
  }
};

void expect_same_float(float got, float want, size_t i) {
  uint32_t a, b;
  std::memcpy(&a, &got, 4);
  std::memcpy(&b, &want, 4);
  EXPECT_EQ(a, b) << "element " << i << ": got " << got << ", want " << want;
}

TEST_F(PlaneIoTest, Fp32PlanesDecodeBitExactly) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> dist(-1e6f, 1e6f);
  for (uint32_t components : {1u, 2u, 3u}) {
    const uint32_t pixels = 333;
    std::vector<float> values(size_t{pixels} * components);
    for (auto& v : values) v = dist(rng);
    values[0] = -0.0f;
    values[1 % values.size()] = 1e-40f;  // subnormal
    values[2 % values.size()] = INFINITY;
    std::vector<uint8_t> bytes(values.size() * 4);
    std::memcpy(bytes.data(), values.data(), bytes.size());
    const auto decoded = decode(bytes, pixels, components);
    for (size_t i = 0; i < values.size(); ++i) expect_same_float(decoded[i], values[i], i);
  }
}

TEST(EmbeddedShaders, AllModulesAreEmbeddedAsSpirv) {
  const auto names = shaders::names();
  for (const char* want : {"passthrough", "accumulate", "plane_probe"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
    const auto code = shaders::get(want);
    ASSERT_GT(code.size(), 5u) << want;
    EXPECT_EQ(code[0], 0x07230203u) << want;  // SPIR-V magic
  }
  EXPECT_TRUE(shaders::get("no_such_shader").empty());
}

TEST_F(PlaneIoTest, KernelCacheSharesIdenticalKernels) {
  gpu::KernelDesc desc;
  desc.name = "plane_probe";
  desc.spirv = shaders::get("plane_probe");
  desc.storage_buffers = 2;
  desc.spec_constants = {{0, 64}, {1, 2}};
  auto a = ctx().kernels().get(desc);
  auto b = ctx().kernels().get(desc);
  EXPECT_EQ(a.get(), b.get());
  desc.spec_constants[1].value = 3;
  EXPECT_NE(ctx().kernels().get(desc).get(), a.get());
  desc.spirv = {};
  EXPECT_THROW(ctx().kernels().get(desc), gpu::Error);
}

}  // namespace
}  // namespace dn
