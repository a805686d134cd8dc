// Bit-identity guard for refactors of the pipeline layer: every pipeline runs
// a few synthetic frames in many channel/format/parameter combinations (split
// mode, TAA, emission, fp16 planes, every motion convention, resets, NaN/Inf
// inputs) and a 64-bit FNV-1a hash of every output frame, the session's device
// bytes and its pass list are compared with tests/pipelines/golden_hashes.txt.
//
// Device output is only reproducible on the same device and driver, so the
// file records the device it came from and the comparison is skipped (hashes
// printed) elsewhere. DN_GOLDEN_OUT=<dir> writes one line per case to
// <dir>/<case>.txt; `cat <dir>/*.txt` after the device line gives a new file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using protocol::MotionConvention;
using test::ChannelId;
using test::Format;

constexpr int kWidth = 37, kHeight = 23;  // odd pixel count: the last output pair is a single pixel
constexpr int kFrames = 6;
constexpr int kResetFrame = 4;

// Deterministic noise in [0, 1) from integers (no std distributions: their
// output is implementation-defined).
float noise(uint32_t a, uint32_t b, uint32_t c) {
  uint32_t h = a * 0x9e3779b1u ^ (b + 0x7f4a7c15u) * 0x85ebca77u ^ (c + 0x165667b1u) * 0xc2b2ae3du;
  h ^= h >> 15;
  h *= 0x2c1b3c6du;
  h ^= h >> 12;
  h *= 0x297a2d39u;
  h ^= h >> 15;
  return static_cast<float>(h >> 8) / 16777216.0f;
}

struct Case {
  std::string name;
  std::string pipeline;
  std::vector<ChannelId> channels;
  Format inputs = Format::F32;
  Format output = Format::F32;
  std::vector<pipelines::ParameterValue> parameters;
  MotionConvention motion = MotionConvention::PixelsToPrevious;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

// Every channel of one frame of a panning scene: tiles of background (depth 0
// or +inf) and three surfaces with their own depth, normal, albedo and
// roughness; a few emitters; ~2% bad samples (NaN, +-Inf, negative, 1e30),
// some zero/tiny albedo, NaN normals, motion and F0, and a roughness of 0.
std::map<ChannelId, std::vector<float>> scene(int t) {
  const int n = kWidth * kHeight;
  const float vx = 1.37f, vy = -0.61f;
  std::map<ChannelId, std::vector<float>> c;
  for (ChannelId id : {ChannelId::Radiance, ChannelId::Diffuse, ChannelId::Specular, ChannelId::Albedo,
                       ChannelId::SpecularF0, ChannelId::Normal, ChannelId::Emission, ChannelId::DiffuseLighting,
                       ChannelId::SpecularLighting, ChannelId::SpecularAlbedo})
    c[id].assign(3 * n, 0.0f);
  c[ChannelId::Roughness].assign(n, 0.0f);
  c[ChannelId::Depth].assign(n, 0.0f);
  c[ChannelId::Motion].assign(2 * n, 0.0f);
  const float specials[] = {NAN, INFINITY, -INFINITY, -1.0f, 1e30f};
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const int i = y * kWidth + x;
      const uint32_t ti = static_cast<uint32_t>(t), ui = static_cast<uint32_t>(i);
      const double u = x + 0.5 + vx * t, v = y + 0.5 + vy * t;
      const int cx = static_cast<int>(std::floor(u / 13.0)), cy = static_cast<int>(std::floor(v / 11.0));
      const uint32_t tile = static_cast<uint32_t>(cx) * 73856093u ^ static_cast<uint32_t>(cy) * 19349663u;
      const int type = static_cast<int>(tile % 6u);
      float albedo[3] = {0.5f, 0.5f, 0.5f}, nrm[3] = {0, 0, 1}, f0[3] = {0.04f, 0.04f, 0.04f};
      float z = 0.0f, rough = 0.3f;
      switch (type) {
        case 0: z = 0.0f; break;
        case 1: z = INFINITY; break;
        case 2:
          z = static_cast<float>(2.0 + 0.002 * u);
          albedo[0] = 0.9f; albedo[1] = 0.4f; albedo[2] = 0.2f;
          rough = 0.05f + 0.4f * static_cast<float>((static_cast<int>(u) / 3) % 4) / 3.0f;
          break;
        case 3:
          z = static_cast<float>(5.0 + 0.003 * v);
          nrm[0] = 0.6f; nrm[2] = 0.8f;
          albedo[0] = 0.2f; albedo[1] = 0.0f; albedo[2] = 5e-4f;
          f0[0] = 1.0f; f0[1] = 0.7f; f0[2] = 0.3f;
          rough = 0.0f;
          break;
        default:
          z = 1.2f;
          nrm[1] = 0.8f; nrm[2] = 0.6f;
          albedo[0] = 0.3f; albedo[1] = 0.3f; albedo[2] = 0.9f;
          rough = 0.8f;
          break;
      }
      const double pattern = 1.0 + 0.5 * std::sin(0.21 * u) * std::cos(0.17 * v);
      const bool emitter = tile % 7u == 3u;
      for (int k = 0; k < 3; ++k) {
        const uint32_t kk = static_cast<uint32_t>(k);
        const float diffuse = static_cast<float>(albedo[k] * pattern * (0.2 + 1.6 * noise(ui, ti, kk)));
        const float specular = static_cast<float>(0.3 * pattern * (0.1 + 1.8 * noise(ui, ti, kk + 3)));
        const float emission = emitter ? 2.0f + static_cast<float>(k) : 0.0f;
        c[ChannelId::Diffuse][3 * i + k] = diffuse;
        c[ChannelId::Specular][3 * i + k] = specular;
        c[ChannelId::Emission][3 * i + k] = emission;
        c[ChannelId::Radiance][3 * i + k] = diffuse + specular + emission;
        c[ChannelId::Albedo][3 * i + k] = albedo[k];
        c[ChannelId::SpecularF0][3 * i + k] = f0[k];
        c[ChannelId::Normal][3 * i + k] = nrm[k];
        // Lighting forms: diffuse without its albedo, specular over a colour.
        c[ChannelId::DiffuseLighting][3 * i + k] = static_cast<float>(pattern * (0.2 + 1.6 * noise(ui, ti, kk)));
        c[ChannelId::SpecularLighting][3 * i + k] = static_cast<float>(specular / (0.5f + f0[k]));
        c[ChannelId::SpecularAlbedo][3 * i + k] = 0.5f + f0[k];
      }
      c[ChannelId::Roughness][i] = rough;
      c[ChannelId::Depth][i] = z;
      c[ChannelId::Motion][2 * i] = vx + 0.4f * (noise(ui, ti, 10) - 0.5f);
      c[ChannelId::Motion][2 * i + 1] = vy + 0.4f * (noise(ui, ti, 11) - 0.5f);
      if (noise(ui, ti, 20) < 0.02f) {
        const float s = specials[static_cast<uint32_t>(noise(ui, ti, 21) * 5) % 5];
        for (ChannelId id : {ChannelId::Radiance, ChannelId::Diffuse, ChannelId::Specular, ChannelId::DiffuseLighting,
                             ChannelId::SpecularLighting})
          c[id][3 * i + (i % 3)] = s;
      }
      if (noise(ui, ti, 22) < 0.005f) c[ChannelId::Normal][3 * i] = NAN;
      if (noise(ui, ti, 23) < 0.005f) c[ChannelId::Motion][2 * i] = NAN;
      if (noise(ui, ti, 24) < 0.005f) c[ChannelId::SpecularF0][3 * i + 1] = NAN;
      if (noise(ui, ti, 26) < 0.005f) c[ChannelId::SpecularAlbedo][3 * i + 2] = NAN;
      if (noise(ui, ti, 25) < 0.005f) c[ChannelId::Roughness][i] = NAN;
    }
  return c;
}

// Column-major camera: perspective (60 degrees) looking down -z from a camera
// that moves along x.
void camera(int t, protocol::Mat4& view, protocol::Mat4& projection) {
  view = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -0.05f * static_cast<float>(t), 0, -3, 1};
  const float f = 1.0f / std::tan(0.5f * 1.0471976f), aspect = static_cast<float>(kWidth) / kHeight;
  const float n = 0.1f, fz = 100.0f;
  projection = {f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (fz + n) / (n - fz), -1, 0, 0, 2 * fz * n / (n - fz), 0};
}

test::HostFrame host_frame(const Case& c, int t) {
  auto values = scene(t);
  test::HostFrame f;
  f.info.frame_index = static_cast<uint64_t>(t);
  f.info.flags = t == kResetFrame ? protocol::kFrameReset : 0u;
  f.info.motion = c.motion;
  camera(t, f.info.view, f.info.projection);
  camera(t - 1, f.info.prev_view, f.info.prev_projection);
  auto& mv = values[ChannelId::Motion];
  for (size_t i = 0; i < mv.size(); ++i) {
    if (c.motion == MotionConvention::PixelsToNext) mv[i] = -mv[i];
    if (c.motion == MotionConvention::UvToPrevious) mv[i] /= static_cast<float>(i % 2 == 0 ? kWidth : kHeight);
  }
  for (ChannelId id : c.channels) f.add(id, c.inputs, values[id]);
  return f;
}

uint64_t fnv1a(uint64_t h, const uint8_t* bytes, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    h ^= bytes[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string hex(uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::vector<Case> cases() {
  using C = ChannelId;
  const std::vector<C> svgf = {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion};
  const std::vector<C> svgf_e = {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission};
  const std::vector<C> split = {C::Diffuse, C::Specular, C::Albedo, C::Normal, C::Depth, C::Motion};
  const std::vector<C> split_e = {C::Diffuse, C::Specular, C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission};
  const std::vector<C> lighting = {C::DiffuseLighting, C::SpecularLighting, C::SpecularAlbedo, C::Albedo,
                                   C::Normal,          C::Depth,            C::Motion,         C::Emission};
  const std::vector<C> split_sa = {C::Diffuse, C::Specular, C::SpecularAlbedo, C::Albedo, C::Normal, C::Depth, C::Motion};
  const std::vector<C> fb = {C::Diffuse, C::Specular, C::Albedo, C::SpecularF0, C::Roughness,
                             C::Normal,  C::Depth,    C::Motion};
  std::vector<C> fb_e = fb;
  fb_e.push_back(C::Emission);
  const std::vector<C> acc = {C::Radiance, C::Normal, C::Depth, C::Motion};
  const auto F16 = Format::F16;
  const auto F32 = Format::F32;
  const std::vector<pipelines::ParameterValue> paper = {{"atrous_iterations", 5}, {"feedback_tap", 0}};
  return {
      {"passthrough_f32", "passthrough", {C::Radiance}, F32, F32, {}},
      {"passthrough_f16_in_extra_channels", "passthrough", {C::Radiance, C::Albedo, C::Normal, C::Depth}, F16, F32, {}},
      {"passthrough_f32_to_f16", "passthrough", {C::Radiance}, F32, F16, {}},
      {"accumulate_f32", "accumulate", acc, F32, F32, {}},
      {"accumulate_f16_uv_params", "accumulate", acc, F16, F16,
       {{"alpha_min", 0.1}, {"max_history", 8}, {"depth_tolerance", 0.05}, {"normal_threshold", 0.8}},
       MotionConvention::UvToPrevious},
      {"accumulate_to_next", "accumulate", acc, F32, F16, {}, MotionConvention::PixelsToNext},
      {"svgf_f32", "svgf", svgf, F32, F32, {}},
      {"svgf_emission", "svgf", svgf_e, F32, F32, {}},
      {"svgf_iter0", "svgf", svgf_e, F32, F32, {{"atrous_iterations", 0}}},
      {"svgf_iter1", "svgf", svgf, F32, F32, {{"atrous_iterations", 1}}},
      {"svgf_paper_f16_uv", "svgf", svgf_e, F16, F16, paper, MotionConvention::UvToPrevious},
      {"svgf_params", "svgf", svgf, F32, F32,
       {{"alpha_colour", 0.1}, {"alpha_moments", 0.3}, {"max_history", 12}, {"phi_colour", 4}, {"phi_normal", 64},
        {"phi_depth", 2}, {"feedback_tap", 2}},
       MotionConvention::PixelsToNext},
      {"svgf_taa", "svgf", svgf_e, F32, F32, {{"taa_alpha", 0.1}}},
      {"svgf_taa_f16", "svgf", svgf, F16, F16, {{"taa_alpha", 0.25}}, MotionConvention::UvToPrevious},
      {"svgf_split", "svgf", split, F32, F32, {}},
      {"svgf_split_f16_emission_taa", "svgf", split_e, F16, F16, {{"taa_alpha", 0.1}}},
      {"svgf_split_iter0", "svgf", split, F32, F32, {{"atrous_iterations", 0}}},
      {"svgf_split_lighting", "svgf", lighting, F32, F32, {}},
      {"svgf_split_lighting_f16", "svgf", lighting, F16, F16, {{"taa_alpha", 0.1}}},
      {"svgf_split_specular_albedo", "svgf", split_sa, F32, F32, {}},
      {"svgf_fb_f32", "svgf-fb", fb, F32, F32, {}},
      {"svgf_fb_emission_taa", "svgf-fb", fb_e, F32, F32, {{"taa_alpha", 0.1}}},
      {"svgf_fb_f16_paper", "svgf-fb", fb_e, F16, F16, paper, MotionConvention::UvToPrevious},
      {"svgf_fb_iter0", "svgf-fb", fb, F32, F16, {{"atrous_iterations", 0}}},
  };
}

// "device driver" of the context: output is compared only on the device the file came from.
std::string device_key(const gpu::Context& ctx) {
  return ctx.name() + " driver " + hex(ctx.properties().driverVersion);
}

struct Golden {
  std::string device;
  std::map<std::string, std::string> lines;  // case -> rest of the line
};

Golden read_golden() {
  Golden g;
  std::ifstream in(DN_GOLDEN_HASHES);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("# device: ", 0) == 0) g.device = line.substr(10);
    if (line.empty() || line[0] == '#') continue;
    const auto space = line.find(' ');
    g.lines[line.substr(0, space)] = line.substr(space + 1);
  }
  return g;
}

class GoldenTest : public test::GpuTest, public testing::WithParamInterface<Case> {};

TEST_P(GoldenTest, OutputIsBitIdentical) {
  const Case& c = GetParam();
  std::vector<pipelines::InputChannel> decls;
  for (ChannelId id : c.channels) decls.push_back({id, c.inputs});
  const auto config = test::make_config(c.pipeline, kWidth, kHeight, decls, c.output, c.parameters);
  // The server's path: prepare once, create from the prepared graph.
  auto prepared = pipelines::prepare(config);
  ASSERT_TRUE(std::holds_alternative<pipelines::PreparedPipeline>(prepared))
      << std::get<pipelines::ConfigError>(prepared).message;
  auto pipe = pipelines::create(ctx(), std::get<pipelines::PreparedPipeline>(prepared));
  EXPECT_EQ(pipe->device_bytes(), std::get<pipelines::PreparedPipeline>(prepared).device_bytes());

  uint64_t hash = 0xcbf29ce484222325ull;
  std::string passes;
  for (int t = 0; t < kFrames; ++t) {
    const test::HostFrame f = host_frame(c, t);
    std::vector<uint8_t> out;
    std::vector<pipelines::PassTiming> timings;
    test::process(*pipe, f.view(), true, out, timings);
    hash = fnv1a(hash, out.data(), out.size());
    if (t == 0)
      for (const auto& timing : timings) passes += (passes.empty() ? "" : ",") + timing.name;
  }
  // The pipeline's own bytes: the constants block is sized by every family's parameter rows.
  const uint64_t own_bytes = pipe->device_bytes() - pipelines::GraphSpec::kConstantBytes;
  const std::string line = hex(hash) + " " + std::to_string(own_bytes) + " " + passes;
  std::printf("[ golden   ] %s %s\n", c.name.c_str(), line.c_str());
  if (const char* dir = std::getenv("DN_GOLDEN_OUT")) {
    std::ofstream(std::string(dir) + "/" + c.name + ".txt") << c.name << " " << line << "\n";
  }

  const Golden golden = read_golden();
  if (golden.device != device_key(ctx()))
    GTEST_SKIP() << "golden hashes are from \"" << golden.device << "\", this is \"" << device_key(ctx()) << "\"";
  const auto it = golden.lines.find(c.name);
  ASSERT_NE(it, golden.lines.end()) << "no golden line for " << c.name;
  EXPECT_EQ(line, it->second) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Pipelines, GoldenTest, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<Case>& info) { return info.param.name; });

}  // namespace
}  // namespace dn
