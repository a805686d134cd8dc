// Bilinear fetch from a storage buffer (shaders/include/bilinear.glsl, the
// way passes read history) against a sampled image with linear filtering, on
// the device the server would choose (--device to pick another). Every pixel
// of a WxH RGBA grid fetches at its centre + (0.3, 0.6) px and writes vec4:
// shaders/bench_bilinear_buffer.comp and bench_bilinear_image.comp, 8x8
// workgroups. Prints one markdown row per size (--size WxH, repeatable;
// default 640x360, 1280x720, 1920x1080): the median device ms of --reps (30)
// timed dispatches for the buffer, an RGBA32F image and an RGBA16F image
// (when the format can be filtered linearly), and the largest difference of
// the fp32 image's output from the buffer's over the interior pixels (a
// check that both compute the same thing).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/shaders/shaders.hpp"
#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/error.hpp"
#include "gpu/timestamps.hpp"
#include "kernel_bench.hpp"
#include "half.hpp"

namespace {

using dn::gpu::check;

constexpr uint32_t kBlock = 8;
constexpr float kOffset[2] = {0.3f, 0.6f};


dn::gpu::GridPush grid_of(uint32_t w, uint32_t h) {
  dn::gpu::GridPush g;
  g.size[0] = g.source[0] = w;
  g.size[1] = g.source[1] = h;
  g.args[0] = std::bit_cast<uint32_t>(kOffset[0]);
  g.args[1] = std::bit_cast<uint32_t>(kOffset[1]);
  return g;
}

class ImageFetch {
 public:
  ImageFetch(dn::gpu::Context& ctx, VkFormat format, uint32_t w, uint32_t h, const std::vector<float>& rgba)
      : ctx_(ctx), device_(ctx.device()), w_(w), h_(h) {
    const bool half = format == VK_FORMAT_R16G16B16A16_SFLOAT;
    const uint64_t bytes = uint64_t{w} * h * 4 * (half ? 2 : 4);
    staging_ = dn::gpu::Buffer(ctx, bytes, dn::gpu::BufferKind::StorageUpload, "image_staging");
    if (half) {
      std::vector<uint16_t> h16(rgba.size());
      for (size_t i = 0; i < rgba.size(); ++i) h16[i] = dn::test::to_half(rgba[i]);
      staging_.write({reinterpret_cast<const uint8_t*>(h16.data()), bytes});
    } else {
      staging_.write({reinterpret_cast<const uint8_t*>(rgba.data()), bytes});
    }

    VkImageCreateInfo ii{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = format;
    ii.extent = {w, h, 1};
    ii.mipLevels = 1;
    ii.arrayLayers = 1;
    ii.samples = VK_SAMPLE_COUNT_1_BIT;
    ii.tiling = VK_IMAGE_TILING_OPTIMAL;
    ii.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    check(vkCreateImage(device_, &ii, nullptr, &image_), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(device_, image_, &req);
    const int type = dn::gpu::find_memory_type(ctx.memory_properties(), req.memoryTypeBits,
                                               VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
    if (type < 0) throw std::runtime_error("no device-local memory for the image");
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = static_cast<uint32_t>(type);
    check(vkAllocateMemory(device_, &ai, nullptr, &memory_), "vkAllocateMemory");
    check(vkBindImageMemory(device_, image_, memory_, 0), "vkBindImageMemory");

    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = image_;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    check(vkCreateImageView(device_, &vi, nullptr, &view_), "vkCreateImageView");

    VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    si.magFilter = si.minFilter = VK_FILTER_LINEAR;
    si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    si.maxLod = 0.0f;
    check(vkCreateSampler(device_, &si, nullptr, &sampler_), "vkCreateSampler");

    const VkDescriptorSetLayoutBinding bindings[2] = {
        {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
        {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
    VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    li.bindingCount = 2;
    li.pBindings = bindings;
    check(vkCreateDescriptorSetLayout(device_, &li, nullptr, &set_layout_), "vkCreateDescriptorSetLayout");
    const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(dn::gpu::GridPush)};
    VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pli.setLayoutCount = 1;
    pli.pSetLayouts = &set_layout_;
    pli.pushConstantRangeCount = 1;
    pli.pPushConstantRanges = &push;
    check(vkCreatePipelineLayout(device_, &pli, nullptr, &layout_), "vkCreatePipelineLayout");

    const auto spirv = dn::shaders::get("bench_bilinear_image");
    if (spirv.empty()) throw std::runtime_error("shader bench_bilinear_image is not embedded");
    VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    mi.codeSize = spirv.size_bytes();
    mi.pCode = spirv.data();
    VkShaderModule module;
    check(vkCreateShaderModule(device_, &mi, nullptr, &module), "vkCreateShaderModule");
    const VkSpecializationMapEntry entry{0, 0, 4};
    const uint32_t block = kBlock;
    const VkSpecializationInfo spec{1, &entry, 4, &block};
    VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_COMPUTE_BIT, module,
                "main", &spec};
    ci.layout = layout_;
    const VkResult r = vkCreateComputePipelines(device_, VK_NULL_HANDLE, 1, &ci, nullptr, &pipeline_);
    vkDestroyShaderModule(device_, module, nullptr);
    check(r, "vkCreateComputePipelines");

    const VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1},
                                           {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1}};
    VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pi.maxSets = 1;
    pi.poolSizeCount = 2;
    pi.pPoolSizes = sizes;
    check(vkCreateDescriptorPool(device_, &pi, nullptr, &pool_), "vkCreateDescriptorPool");
    VkDescriptorSetAllocateInfo dai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    dai.descriptorPool = pool_;
    dai.descriptorSetCount = 1;
    dai.pSetLayouts = &set_layout_;
    check(vkAllocateDescriptorSets(device_, &dai, &set_), "vkAllocateDescriptorSets");
  }

  ~ImageFetch() {
    if (pool_) vkDestroyDescriptorPool(device_, pool_, nullptr);
    if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
    if (layout_) vkDestroyPipelineLayout(device_, layout_, nullptr);
    if (set_layout_) vkDestroyDescriptorSetLayout(device_, set_layout_, nullptr);
    if (sampler_) vkDestroySampler(device_, sampler_, nullptr);
    if (view_) vkDestroyImageView(device_, view_, nullptr);
    if (image_) vkDestroyImage(device_, image_, nullptr);
    if (memory_) vkFreeMemory(device_, memory_, nullptr);
  }

  void bind_result(const dn::gpu::Buffer& result) {
    const VkDescriptorBufferInfo bi{result.handle(), 0, VK_WHOLE_SIZE};
    const VkDescriptorImageInfo ii{sampler_, view_, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet writes[2] = {{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}, {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}};
    writes[0].dstSet = writes[1].dstSet = set_;
    writes[0].dstBinding = 1;
    writes[0].descriptorCount = 1;
    writes[0].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[0].pBufferInfo = &bi;
    writes[1].dstBinding = 2;
    writes[1].descriptorCount = 1;
    writes[1].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[1].pImageInfo = &ii;
    vkUpdateDescriptorSets(device_, 2, writes, 0, nullptr);
  }

  // The staging copy into the image with its layout transitions.
  void record_upload(VkCommandBuffer cmd) const {
    staging_.record_upload(cmd, staging_.size());
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_HOST_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image_;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {w_, h_, 1};
    vkCmdCopyBufferToImage(cmd, staging_.handle(), image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0,
                         nullptr, 1, &b);
  }

  void record_dispatch(VkCommandBuffer cmd) const {
    const dn::gpu::GridPush g = grid_of(w_, h_);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
    vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof g, &g);
    vkCmdDispatch(cmd, (w_ + kBlock - 1) / kBlock, (h_ + kBlock - 1) / kBlock, 1);
  }

 private:
  dn::gpu::Context& ctx_;
  VkDevice device_;
  uint32_t w_, h_;
  dn::gpu::Buffer staging_;
  VkImage image_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  VkSampler sampler_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
};

bool filterable(dn::gpu::Context& ctx, VkFormat format) {
  VkFormatProperties p;
  vkGetPhysicalDeviceFormatProperties(ctx.physical_device(), format, &p);
  return p.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
}

void run(dn::gpu::Context& ctx, uint32_t w, uint32_t h, int reps) {
  const std::vector<float> rgba = dn::bench::random_rgba(w, h);
  const uint64_t bytes = rgba.size() * 4;

  // Buffer fetch.
  dn::gpu::Buffer source(ctx, bytes, dn::gpu::BufferKind::StorageUpload, "source");
  source.write({reinterpret_cast<const uint8_t*>(rgba.data()), bytes});
  dn::gpu::Buffer result(ctx, bytes, dn::gpu::BufferKind::StorageDownload, "result");
  dn::gpu::Buffer uniform(ctx, 256, dn::gpu::BufferKind::Constants, "unused");
  dn::gpu::KernelDesc desc;
  desc.name = "bench_bilinear_buffer";
  desc.spirv = dn::shaders::get("bench_bilinear_buffer");
  desc.storage_buffers = 2;
  desc.local_size_x = desc.local_size_y = kBlock;
  desc.push_constant_bytes = sizeof(dn::gpu::GridPush);
  auto kernel = ctx.kernels().get(desc);
  dn::gpu::DescriptorPool pool(ctx, 1, 2);
  const VkBuffer storage[2] = {result.handle(), source.handle()};
  VkDescriptorSet set = pool.allocate(*kernel, uniform.handle(), storage);
  const double buffer_ms = dn::bench::time_dispatches(
      ctx, result, reps, [&](VkCommandBuffer cmd) { kernel->record_dispatch(cmd, set, grid_of(w, h)); },
      [&](VkCommandBuffer cmd) {
        source.record_upload(cmd, bytes);
        dn::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
      });
  const auto from_buffer = dn::bench::read_floats(result);

  std::optional<double> image_ms[2];
  double max_diff = NAN;
  const VkFormat formats[2] = {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R16G16B16A16_SFLOAT};
  for (int f = 0; f < 2; ++f) {
    if (!filterable(ctx, formats[f])) continue;
    ImageFetch image(ctx, formats[f], w, h, rgba);
    dn::gpu::Buffer image_result(ctx, bytes, dn::gpu::BufferKind::StorageDownload, "image_result");
    image.bind_result(image_result);
    image_ms[f] = dn::bench::time_dispatches(
        ctx, image_result, reps, [&](VkCommandBuffer cmd) { image.record_dispatch(cmd); },
        [&](VkCommandBuffer cmd) { image.record_upload(cmd); });
    if (f == 0) {
      const auto from_image = dn::bench::read_floats(image_result);
      max_diff = 0.0;
      for (uint32_t y = 0; y + 1 < h; ++y)
        for (uint32_t x = 0; x + 1 < w; ++x)
          for (int c = 0; c < 4; ++c) {
            const size_t i = (size_t{y} * w + x) * 4 + c;
            max_diff = std::max(max_diff, double(std::abs(from_image[i] - from_buffer[i])));
          }
    }
  }
  auto cell = [](const std::optional<double>& v) {
    if (!v) return std::string("unsupported");
    char s[32];
    std::snprintf(s, sizeof s, "%.3f", *v);
    return std::string(s);
  };
  std::printf("| %ux%u | %.3f | %s | %s | %.2g |\n", w, h, buffer_ms, cell(image_ms[0]).c_str(),
              cell(image_ms[1]).c_str(), max_diff);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  dn::bench::KernelBenchOptions options;
  options.reps = 30;
  if (!dn::bench::parse_kernel_bench_args(argc, argv, "bilinear_bench", options)) return 2;
  if (options.sizes.empty()) options.sizes = {{640, 360}, {1280, 720}, {1920, 1080}};
  return dn::bench::run_on_device("bilinear_bench", options, [&](dn::gpu::Context& ctx) {
    std::printf("device: %s; median device ms of %d dispatches, one bilinear fetch per pixel\n\n",
                ctx.name().c_str(), options.reps);
    std::printf("| size | buffer fp32 (bilinear.glsl) | image RGBA32F | image RGBA16F | max diff fp32 |\n");
    std::printf("| --- | --- | --- | --- | --- |\n");
    for (auto [w, h] : options.sizes) run(ctx, w, h, options.reps);
  });
}
