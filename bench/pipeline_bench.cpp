// Pipeline speed against the copy floor.
//
// For every pipeline (or --pipeline NAME) and size (--size WxH, repeatable;
// default 640x360 and 1280x720) it opens a session on the device the server
// would choose (--device to pick another), feeds it --frames frames (default
// 12, the first --warmup 2 not counted) of deterministic noisy radiance and
// smooth G-buffers seen by a panning camera (and, for the stat pipelines,
// the sample statistics of 4 samples per pixel; --param NAME=VALUE sets a
// parameter of every benched pipeline), and prints one markdown row:
// cold figures apart from steady ones (create() wall time with the number of
// kernels it compiled, the first frame's device time), then
// the median device time of every pass (from the timings process() returns),
// the median of their sum, upload and download, the persistent device bytes
// per pixel, and the copy floor measured in the same run.
//
// Copy floor. The least traffic a frame of the session needs is taken to be
// device_bytes(): every byte the session holds on the device read or written
// once (inputs read, output written, previous history read, current history
// written, scratch written). With no scratch this is exactly
// input + 2 x history + output. The floor is a plain compute copy
// (shaders/bench_copy.comp) that moves the same number of bytes: it reads
// device_bytes()/2 and writes device_bytes()/2, timed with Vulkan timestamps,
// median of --copy-reps (10) submissions. "ratio" = pipeline device ms / floor ms.
//
// Only the public pipeline API (pipeline.hpp) and the gpu layer are used, so
// the benchmark follows pipelines as their passes change.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dn/protocol/channels.hpp"
#include "dn/protocol/messages.hpp"
#include "dn/shaders/shaders.hpp"
#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/error.hpp"
#include "gpu/timestamps.hpp"
#include "online_stats.hpp"
#include "half.hpp"
#include "session/frame_planes.hpp"
#include "pipelines/pipeline.hpp"

namespace {

using dn::protocol::ChannelId;
using dn::protocol::Format;

struct Options {
  std::vector<std::string> pipelines;
  std::vector<std::pair<uint32_t, uint32_t>> sizes;
  Format format = Format::F32;
  std::string device;
  int frames = 12;
  int warmup = 2;
  int copy_reps = 10;
  std::vector<dn::pipelines::ParameterValue> parameters;  // --param NAME=VALUE, for every pipeline benched
  int sample_period = 1;  // --spp 1/k: a sample_count plane, each pixel sampled once in k frames
};

[[noreturn]] void usage(const char* argv0, int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: %s [--pipeline NAME]... [--size WxH]... [--fp16] [--device SELECTOR]\n"
               "          [--frames N] [--warmup N] [--copy-reps N] [--param NAME=VALUE]... [--spp-period K]\n"
               "--spp-period K (> 1): pipelines that take sample_count (progressive) get one, each pixel\n"
               "sampled once in every K frames ((x + 2y + t) mod K = 0; radiance 0 elsewhere).\n"
               "Per-pass device time of each pipeline against a plain copy of the same bytes.\n",
               argv0);
  std::exit(code);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        usage(argv[0], 2);
      }
      return argv[++i];
    };
    auto count = [&](int min) {
      const std::string v = value();
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (!end || *end || n < min || n > 100000) {
        std::fprintf(stderr, "%s: bad value %s\n", a.c_str(), v.c_str());
        usage(argv[0], 2);
      }
      return static_cast<int>(n);
    };
    if (a == "--pipeline") {
      o.pipelines.push_back(value());
    } else if (a == "--size") {
      const std::string v = value();
      unsigned w = 0, h = 0;
      char tail = 0;
      if (std::sscanf(v.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0) {
        std::fprintf(stderr, "--size: expected WxH, got %s\n", v.c_str());
        usage(argv[0], 2);
      }
      o.sizes.emplace_back(w, h);
    } else if (a == "--fp16") {
      o.format = Format::F16;
    } else if (a == "--device") {
      o.device = value();
    } else if (a == "--frames") {
      o.frames = count(1);
    } else if (a == "--warmup") {
      o.warmup = count(0);
    } else if (a == "--copy-reps") {
      o.copy_reps = count(1);
    } else if (a == "--param") {
      const std::string v = value();
      const size_t eq = v.find('=');
      char* end = nullptr;
      const double x = eq == std::string::npos ? 0.0 : std::strtod(v.c_str() + eq + 1, &end);
      if (eq == std::string::npos || eq == 0 || !end || *end) {
        std::fprintf(stderr, "--param: expected NAME=VALUE, got %s\n", v.c_str());
        usage(argv[0], 2);
      }
      o.parameters.push_back({v.substr(0, eq), x});
    } else if (a == "--spp-period") {
      o.sample_period = count(1);
    } else if (a == "--help" || a == "-h") {
      usage(argv[0], 0);
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      usage(argv[0], 2);
    }
  }
  if (o.sizes.empty()) o.sizes = {{640, 360}, {1280, 720}};
  if (o.pipelines.empty())
    for (const auto& d : dn::pipelines::available_pipelines()) o.pipelines.push_back(d.name);
  if (o.warmup >= o.frames) {
    std::fprintf(stderr, "--warmup must be less than --frames\n");
    usage(argv[0], 2);
  }
  return o;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// ---------------------------------------------------------------------------
// Synthetic frames: a smooth height field seen by a camera panning at
// (kPanX, kPanY) pixels per frame. Depth, normals and albedo are smooth
// functions of the world position; radiance is albedo x shading x unit-mean
// exponential noise; motion is the camera motion plus a little per-pixel noise
// (pixels to the previous frame, p_prev = p + mv). Everything is a function
// of (frame, pixel) only, so runs are repeatable.

constexpr float kPanX = 1.5f, kPanY = 0.5f;

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Uniform in (0, 1).
float uniform01(uint64_t& state) {
  state = splitmix64(state);
  return (static_cast<float>(state >> 40) + 0.5f) * (1.0f / 16777216.0f);
}

float depth_at(double u, double v) {
  return static_cast<float>(5.0 + 2.0 * std::sin(u * 0.013) * std::cos(v * 0.017) + 0.5 * std::sin(u * 0.041 + v * 0.029));
}

// Samples per pixel behind the sample statistics planes.
constexpr int kStatSamples = 4;

struct HostPlanes {
  std::map<ChannelId, std::vector<float>> values;
};

HostPlanes make_planes(uint32_t w, uint32_t h, int t, uint64_t needed, int sample_period) {
  HostPlanes p;
  const size_t n = size_t{w} * h;
  auto want = [&](ChannelId id) { return (needed & dn::protocol::channel_bit(id)) != 0; };
  std::vector<float> radiance(3 * n), albedo(3 * n), normal(3 * n), depth(n), motion(2 * n), emission;
  if (want(ChannelId::Emission)) emission.assign(3 * n, 0.0f);
  const float light[3] = {0.3f, 0.5f, 0.812404f};  // unit
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = size_t{y} * w + x;
      uint64_t rng = splitmix64((uint64_t(uint32_t(t)) << 40) ^ i);
      const double u = x + 0.5 + double(kPanX) * t, v = y + 0.5 + double(kPanY) * t;  // world position
      const float z = depth_at(u, v);
      depth[i] = z;
      // Normal of the height field z(u, v) (central differences), unit length.
      const float dzdu = 0.5f * (depth_at(u + 1, v) - depth_at(u - 1, v));
      const float dzdv = 0.5f * (depth_at(u, v + 1) - depth_at(u, v - 1));
      float nx = -8.0f * dzdu, ny = -8.0f * dzdv, nz = 1.0f;
      const float len = std::sqrt(nx * nx + ny * ny + nz * nz);
      nx /= len, ny /= len, nz /= len;
      normal[3 * i] = nx, normal[3 * i + 1] = ny, normal[3 * i + 2] = nz;
      const float shade = 0.05f + 2.0f * std::max(0.0f, nx * light[0] + ny * light[1] + nz * light[2]);
      for (int c = 0; c < 3; ++c) {
        const float a = 0.5f + 0.4f * static_cast<float>(std::sin(u * (0.021 + 0.007 * c) + 1.3 * c) *
                                                         std::cos(v * (0.019 + 0.005 * c)));
        albedo[3 * i + c] = a;  // in [0.1, 0.9]
        radiance[3 * i + c] = a * shade * -std::log(uniform01(rng));
      }
      motion[2 * i] = kPanX + 0.25f * (2.0f * uniform01(rng) - 1.0f);
      motion[2 * i + 1] = kPanY + 0.25f * (2.0f * uniform01(rng) - 1.0f);
    }
  }
  // Split lighting (svgf-fb): 70 % diffuse and 30 % specular of the same
  // noisy samples, the F0 of a dielectric, roughness varying over [0.05, 0.65].
  if (want(ChannelId::Diffuse) || want(ChannelId::Specular)) {
    std::vector<float> diffuse(3 * n), specular(3 * n), f0(3 * n, 0.04f), roughness(n);
    for (size_t i = 0; i < 3 * n; ++i) {
      diffuse[i] = 0.7f * radiance[i];
      specular[i] = 0.3f * radiance[i];
    }
    for (size_t i = 0; i < n; ++i) roughness[i] = 0.35f + 0.3f * std::sin(0.05f * float(i % w) + 0.03f * float(i / w));
    p.values[ChannelId::Diffuse] = std::move(diffuse);
    p.values[ChannelId::Specular] = std::move(specular);
    if (want(ChannelId::SpecularF0)) p.values[ChannelId::SpecularF0] = std::move(f0);
    if (want(ChannelId::Roughness)) p.values[ChannelId::Roughness] = std::move(roughness);
  }
  // Reflection features (reflect): a mirror-like surface 1 unit above the
  // height field, seen straight down: the reflected point is the pixel's own
  // point raised by 1, with the field's normal and albedo.
  if (want(ChannelId::ReflectionPosition)) {
    std::vector<float> position(3 * n), reflected(3 * n), direction(3 * n), rdepth(n), distance(n, 1.0f);
    for (size_t i = 0; i < n; ++i) {
      const float x = float(i % w) + kPanX * float(t), y = float(i / w) + kPanY * float(t);
      position[3 * i] = reflected[3 * i] = x;
      position[3 * i + 1] = reflected[3 * i + 1] = y;
      position[3 * i + 2] = depth[i];
      reflected[3 * i + 2] = depth[i] + 1.0f;
      direction[3 * i + 2] = 1.0f;
      rdepth[i] = depth[i] + 1.0f;
    }
    p.values[ChannelId::Position] = std::move(position);
    p.values[ChannelId::ReflectionPosition] = std::move(reflected);
    p.values[ChannelId::ReflectionAlbedo] = albedo;
    p.values[ChannelId::ReflectionNormal] = normal;
    p.values[ChannelId::ReflectionDepth] = std::move(rdepth);
    p.values[ChannelId::ReflectionDirection] = std::move(direction);
    p.values[ChannelId::ReflectionDistance] = std::move(distance);
  }
  // Sample statistics (stat, stat-temporal): kStatSamples exponential
  // samples per pixel around the radiance's mean, accumulated as dnrender
  // does (paper 003 Alg. 1); the radiance is their raw mean.
  if (want(ChannelId::StatCount)) {
    std::vector<float> count(n, float(kStatSamples)), mean(3 * n), m2(3 * n), m3(3 * n);
    for (size_t i = 0; i < 3 * n; ++i) {
      uint64_t rng = splitmix64((uint64_t(uint32_t(t)) << 40) ^ (i + 0x5bd1e995u));
      const float truth = radiance[i] > 0.0f ? radiance[i] : 0.0f;
      dn::render::OnlineStats acc;
      for (int k = 0; k < kStatSamples; ++k) acc.add(truth * -std::log(uniform01(rng)));
      mean[i] = acc.mean, m2[i] = acc.m2, m3[i] = acc.m3, radiance[i] = acc.raw_mean;
    }
    p.values[ChannelId::StatCount] = std::move(count);
    p.values[ChannelId::StatMean] = std::move(mean);
    p.values[ChannelId::StatM2] = std::move(m2);
    p.values[ChannelId::StatM3] = std::move(m3);
  }
  // Fewer than one sample per pixel: the mask, and no radiance where it is 0.
  if (want(ChannelId::SampleCount)) {
    std::vector<float> count(n);
    for (size_t i = 0; i < n; ++i) {
      count[i] = (i % w + 2 * (i / w) + size_t(t)) % size_t(sample_period) == 0 ? 1.0f : 0.0f;
      if (count[i] == 0.0f)
        for (int c = 0; c < 3; ++c) radiance[3 * i + c] = 0.0f;
    }
    p.values[ChannelId::SampleCount] = std::move(count);
  }
  if (want(ChannelId::Radiance)) p.values[ChannelId::Radiance] = std::move(radiance);
  if (want(ChannelId::Albedo)) p.values[ChannelId::Albedo] = std::move(albedo);
  if (want(ChannelId::Normal)) p.values[ChannelId::Normal] = std::move(normal);
  if (want(ChannelId::Depth)) p.values[ChannelId::Depth] = std::move(depth);
  if (want(ChannelId::Motion)) p.values[ChannelId::Motion] = std::move(motion);
  if (want(ChannelId::Emission)) p.values[ChannelId::Emission] = std::move(emission);
  return p;
}

std::vector<uint8_t> encode(const std::vector<float>& values, Format format) {
  std::vector<uint8_t> out(values.size() * dn::protocol::bytes_per_component(format));
  if (format == Format::F32) {
    std::memcpy(out.data(), values.data(), out.size());
  } else {
    for (size_t i = 0; i < values.size(); ++i) {
      const uint16_t h = dn::test::to_half(values[i]);
      std::memcpy(out.data() + 2 * i, &h, 2);
    }
  }
  return out;
}

// Column-major translation: the view matrix of a camera at (cx, cy, 0).
dn::protocol::Mat4 view_matrix(float cx, float cy) {
  dn::protocol::Mat4 m{};
  m[0] = m[5] = m[10] = m[15] = 1.0f;
  m[12] = -cx;
  m[13] = -cy;
  return m;
}

struct EncodedFrame {
  std::vector<std::vector<uint8_t>> bytes;
  dn::protocol::Frame frame;
  uint64_t input_bytes = 0;
};

EncodedFrame make_frame(const dn::pipelines::SessionConfig& config, int t, int sample_period) {
  uint64_t needed = 0;
  for (const auto& c : config.channels) needed |= dn::protocol::channel_bit(c.id);
  HostPlanes planes = make_planes(config.width, config.height, t, needed, sample_period);
  EncodedFrame f;
  f.bytes.reserve(config.channels.size());
  f.frame.info.frame_index = static_cast<uint64_t>(t);
  f.frame.info.flags = t == 0 ? dn::protocol::kFrameReset : 0u;
  f.frame.info.motion = dn::protocol::MotionConvention::PixelsToPrevious;
  f.frame.info.view = view_matrix(kPanX * t, kPanY * t);
  f.frame.info.prev_view = view_matrix(kPanX * (t - 1), kPanY * (t - 1));
  dn::protocol::Mat4 identity{};
  identity[0] = identity[5] = identity[10] = identity[15] = 1.0f;
  f.frame.info.projection = f.frame.info.prev_projection = identity;
  for (const auto& c : config.channels) {
    f.bytes.push_back(encode(planes.values.at(c.id), c.format));
    f.frame.planes.push_back({c.id, c.format, f.bytes.back()});
    f.input_bytes += f.bytes.back().size();
  }
  return f;
}

// The channels a session of `desc` declares: the required ones (svgf-fb
// requires specular, F0 and roughness), plus radiance where it is only
// optional (svgf), or diffuse where the pipeline takes no radiance (svgf-fb,
// reflect: diffuse or diffuse_lighting, one is needed); optional split
// lighting and emission would add passes to svgf, so they are left out there
// and the svgf row stays comparable.
std::vector<dn::pipelines::InputChannel> channels_for(const dn::pipelines::PipelineDescription& desc, Format format,
                                                     int sample_period) {
  std::vector<dn::pipelines::InputChannel> out;
  // The sample statistics are fp32 only (docs/protocol.md §7.7).
  for (const auto& c : dn::protocol::kChannels)
    if (desc.required_channels & dn::protocol::channel_bit(c.id))
      out.push_back({c.id, dn::protocol::is_sample_statistic(c.id) ? Format::F32 : format});
  // svgf takes radiance or diffuse + specular, so radiance is optional there: send it.
  const uint64_t radiance = dn::protocol::channel_bit(dn::protocol::ChannelId::Radiance);
  if (!(desc.required_channels & radiance) && (desc.optional_channels & radiance))
    out.insert(out.begin(), {dn::protocol::ChannelId::Radiance, format});
  // svgf-fb and reflect require specular and take diffuse in either form: send it.
  const uint64_t diffuse = dn::protocol::channel_bit(dn::protocol::ChannelId::Diffuse);
  if (!((desc.required_channels | desc.optional_channels) & radiance) && (desc.optional_channels & diffuse))
    out.insert(out.begin(), {dn::protocol::ChannelId::Diffuse, format});
  const uint64_t mask = dn::protocol::channel_bit(dn::protocol::ChannelId::SampleCount);
  if (sample_period > 1 && (desc.optional_channels & mask)) out.push_back({dn::protocol::ChannelId::SampleCount, format});
  return out;
}

// ---------------------------------------------------------------------------
// Copy floor: bench_copy over `bytes` bytes (read bytes, write bytes), split
// into chunks no larger than the device's storage-buffer range.

class CopyFloor {
 public:
  explicit CopyFloor(dn::gpu::Context& context) : context_(context) {
    dn::gpu::KernelDesc desc;
    desc.name = "bench_copy";
    desc.spirv = dn::shaders::get("bench_copy");
    if (desc.spirv.empty()) throw std::runtime_error("shader bench_copy is not embedded");
    desc.storage_buffers = 2;
    desc.spec_constants.push_back({0, kWorkgroupSize});
    kernel_ = context.kernels().get(desc);
    commands_ = std::make_unique<dn::gpu::CommandStream>(context);
    timestamps_ = std::make_unique<dn::gpu::TimestampPool>(context, 2);
  }

  // Median device ms of `reps` timed copies of `bytes` bytes.
  double measure(uint64_t bytes, int reps) {
    bytes = std::max<uint64_t>(4, bytes & ~uint64_t{3});
    const uint64_t limit = std::min<uint64_t>(context_.limits().max_storage_buffer_range,
                                              context_.limits().max_memory_allocation_size) &
                           ~uint64_t{3};
    struct Chunk {
      dn::gpu::Buffer src, dst, constants;
      VkDescriptorSet forward = VK_NULL_HANDLE, backward = VK_NULL_HANDLE;
      uint32_t groups = 1;
    };
    const uint64_t count = (bytes + limit - 1) / limit;
    std::vector<Chunk> chunks(count);
    dn::gpu::DescriptorPool pool(context_, static_cast<uint32_t>(2 * count), static_cast<uint32_t>(4 * count));
    uint64_t left = bytes;
    for (auto& c : chunks) {
      const uint64_t size = std::min(left, limit);
      left -= size;
      c.src = dn::gpu::Buffer(context_, size, dn::gpu::BufferKind::Storage, "copy_src");
      c.dst = dn::gpu::Buffer(context_, size, dn::gpu::BufferKind::Storage, "copy_dst");
      c.constants = dn::gpu::Buffer(context_, 16, dn::gpu::BufferKind::Constants, "copy_constants");
      const uint32_t words[4] = {static_cast<uint32_t>(size / 4), 0, 0, 0};
      c.constants.write({reinterpret_cast<const uint8_t*>(words), sizeof words});
      const VkBuffer fwd[2] = {c.src.handle(), c.dst.handle()};
      const VkBuffer bwd[2] = {c.dst.handle(), c.src.handle()};
      c.forward = pool.allocate(*kernel_, c.constants.handle(), fwd);
      c.backward = pool.allocate(*kernel_, c.constants.handle(), bwd);
      // About 4 words per invocation, grid-stride beyond the group-count limit.
      const uint64_t groups = (size / 4 + 4 * kWorkgroupSize - 1) / (4 * kWorkgroupSize);
      c.groups = static_cast<uint32_t>(
          std::clamp<uint64_t>(groups, 1, context_.limits().max_compute_work_group_count[0]));
    }

    auto run = [&](bool backward, bool fill) {
      VkCommandBuffer cmd = commands_->begin();
      timestamps_->reset(cmd);
      dn::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                              VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                              VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                              VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
      if (fill) {
        // Real, non-zero source pages (untouched memory could read as a
        // shared zero page on a CPU device and flatter the copy).
        for (auto& c : chunks) vkCmdFillBuffer(cmd, c.src.handle(), 0, VK_WHOLE_SIZE, 0x3f800000u);
        dn::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
      }
      timestamps_->write(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0);
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel_->pipeline());
      for (auto& c : chunks) {
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel_->layout(), 0, 1,
                                backward ? &c.backward : &c.forward, 0, nullptr);
        vkCmdDispatch(cmd, c.groups, 1, 1);
      }
      timestamps_->write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 1);
      commands_->submit_and_wait();
      return timestamps_->read_intervals_ms(2).at(0);
    };
    run(false, true);  // fill the source, fault in the destination
    run(true, false);  // and the other way round
    std::vector<double> ms;
    for (int r = 0; r < reps; ++r) ms.push_back(run(false, false));
    return median(ms);
  }

 private:
  static constexpr uint32_t kWorkgroupSize = 64;
  dn::gpu::Context& context_;
  std::shared_ptr<const dn::gpu::Kernel> kernel_;
  std::unique_ptr<dn::gpu::CommandStream> commands_;
  std::unique_ptr<dn::gpu::TimestampPool> timestamps_;
};

// ---------------------------------------------------------------------------

struct Row {
  std::string pipeline;
  uint32_t width = 0, height = 0;
  std::string passes;  // "name ms · name ms"
  double device_ms = 0, upload_ms = 0, download_ms = 0;
  double bytes_per_pixel = 0;
  double transient_per_pixel = 0;  // of bytes_per_pixel, scratch leased per frame from the device's pool
  double create_ms = 0;       // pipelines::create, wall clock: compiling (first use in this process) + allocating
  uint64_t compiled = 0;      // kernels that create() compiled
  double first_frame_ms = 0;  // device time of the first frame (cold: first dispatch of each kernel)
  uint64_t floor_bytes = 0;
  double copy_ms = 0;
  std::string error;
};

std::string fmt_ms(double ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, ms >= 100 ? "%.0f" : ms >= 10 ? "%.1f" : "%.2f", ms);
  return buf;
}

Row bench_one(dn::gpu::Context& context, CopyFloor& copy, const Options& o,
              const dn::pipelines::PipelineDescription& desc, uint32_t w, uint32_t h) {
  Row row;
  row.pipeline = desc.name;
  row.width = w;
  row.height = h;
  dn::pipelines::SessionConfig config;
  config.width = w;
  config.height = h;
  config.pipeline = desc.name;
  config.output_format = o.format;
  config.channels = channels_for(desc, o.format, o.sample_period);
  config.parameters = o.parameters;
  if (auto err = dn::pipelines::validate(config)) {
    row.error = err->field + ": " + err->message;
    return row;
  }
  std::unique_ptr<dn::pipelines::Pipeline> pipe;
  try {
    const uint64_t kernels_before = context.kernels().stats().kernels;
    const auto start = std::chrono::steady_clock::now();
    pipe = dn::pipelines::create(context, config);
    row.create_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    row.compiled = context.kernels().stats().kernels - kernels_before;
  } catch (const std::exception& e) {
    row.error = e.what();
    return row;
  }
  const uint64_t pixels = uint64_t{w} * h;
  row.bytes_per_pixel = static_cast<double>(pipe->device_bytes()) / static_cast<double>(pixels);
  row.transient_per_pixel = static_cast<double>(pipe->transient_bytes()) / static_cast<double>(pixels);

  std::map<std::string, std::vector<double>> times;
  std::vector<std::string> order;
  std::vector<double> totals;
  std::vector<uint8_t> output;
  for (int t = 0; t < o.frames; ++t) {
    EncodedFrame f = make_frame(config, t, o.sample_period);
    std::vector<dn::pipelines::PassTiming> timings;
    pipe->process(dn::server::frame_planes_or_throw(f.frame, config), true, output, timings);
    if (t == 0)
      for (const auto& tm : timings)
        if (tm.name != "upload" && tm.name != "download") row.first_frame_ms += tm.milliseconds;
    if (t < o.warmup) continue;
    double sum = 0;
    for (const auto& tm : timings) {
      if (!times.count(tm.name)) order.push_back(tm.name);
      times[tm.name].push_back(tm.milliseconds);
      if (tm.name != "upload" && tm.name != "download") sum += tm.milliseconds;
    }
    totals.push_back(sum);
  }
  for (const auto& name : order) {
    if (name == "upload" || name == "download") continue;
    if (!row.passes.empty()) row.passes += " · ";
    row.passes += name + " " + fmt_ms(median(times[name]));
  }
  row.device_ms = median(totals);
  row.upload_ms = median(times["upload"]);
  row.download_ms = median(times["download"]);
  row.floor_bytes = pipe->device_bytes();
  pipe.reset();  // free its memory before the copy allocates
  // The copy moves floor_bytes: reads half of them and writes the other half.
  row.copy_ms = copy.measure(row.floor_bytes / 2, o.copy_reps);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::string command;
  for (int i = 0; i < argc; ++i) command += (i ? " " : "") + std::string(argv[i]);
  try {
    dn::gpu::ContextOptions context_options;
    context_options.device = o.device;
    dn::gpu::Context context(context_options);
    const auto& pipelines = dn::pipelines::available_pipelines();
    for (const auto& name : o.pipelines) {
      if (std::none_of(pipelines.begin(), pipelines.end(), [&](const auto& d) { return d.name == name; })) {
        std::fprintf(stderr, "unknown pipeline %s; available:", name.c_str());
        for (const auto& d : pipelines) std::fprintf(stderr, " %s", d.name.c_str());
        std::fprintf(stderr, "\n");
        return 2;
      }
    }
    std::printf("command: `%s`\n", command.c_str());
    std::printf("device: %s (%s)%s\n", context.name().c_str(), context.info().driver.c_str(),
                context.validation_enabled() ? " [validation ON: timings are not representative]" : "");
    std::printf("planes: %s inputs and output; %d frames per session, first %d not counted; medians\n\n",
                o.format == Format::F16 ? "fp16" : "fp32", o.frames, o.warmup);
    std::printf("| pipeline | size | create ms (kernels compiled) | first frame device ms | passes (median ms) "
                "| device ms | upload ms | download ms | device B/px (persistent + pooled) | floor MB | copy floor ms "
                "| pipeline / copy |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::fflush(stdout);

    CopyFloor copy(context);
    int failures = 0;
    for (const auto& name : o.pipelines) {
      const auto& desc = *std::find_if(pipelines.begin(), pipelines.end(), [&](const auto& d) { return d.name == name; });
      for (const auto& [w, h] : o.sizes) {
        Row r = bench_one(context, copy, o, desc, w, h);
        if (!r.error.empty()) {
          std::printf("| %s | %ux%u | failed: %s | | | | | | | | | |\n", r.pipeline.c_str(), w, h, r.error.c_str());
          ++failures;
        } else {
          std::printf("| %s | %ux%u | %s (%llu) | %s | %s | %s | %s | %s | %.0f (%.0f + %.0f) | %.1f | %s | %.1f× |\n",
                      r.pipeline.c_str(), w, h, fmt_ms(r.create_ms).c_str(), static_cast<unsigned long long>(r.compiled),
                      fmt_ms(r.first_frame_ms).c_str(), r.passes.c_str(), fmt_ms(r.device_ms).c_str(), fmt_ms(r.upload_ms).c_str(),
                      fmt_ms(r.download_ms).c_str(), r.bytes_per_pixel, r.bytes_per_pixel - r.transient_per_pixel,
                      r.transient_per_pixel, r.floor_bytes / 1e6,
                      fmt_ms(r.copy_ms).c_str(), r.copy_ms > 0 ? r.device_ms / r.copy_ms : 0.0);
        }
        std::fflush(stdout);
      }
    }
    std::printf(
        "\nfloor MB = device_bytes(): the least traffic per frame if every byte the session holds on the device "
        "is read or written once (inputs read, output written, previous history read, current history written, "
        "scratch written); = inputs + 2 x history + output when a pipeline has no scratch. create ms: "
        "pipelines::create wall clock, cold (it compiles) for the first size of a pipeline in this process, warm "
        "after; first frame: device time of frame 0, not in the medians. copy floor = "
        "bench_copy reading floor/2 bytes and writing floor/2 bytes, Vulkan timestamps, median of %d.\n",
        o.copy_reps);
    if (context.validation_enabled())
      std::printf("validation messages: %llu\n", static_cast<unsigned long long>(context.validation_message_count()));
    return failures || context.validation_message_count() ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pipeline_bench: %s\n", e.what());
    return 1;
  }
}
