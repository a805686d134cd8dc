// The still scene of the hard-case suites (guide_hard_cases_test.cpp: bad
// guides; radiance_hard_cases_test.cpp: extreme light, both output formats):
// every pipeline as a session opens it, a clean 32x16 frame of every channel,
// and frames whose patch of one channel holds other values.
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

#include "gpu_test_env.hpp"
#include "svgf_inputs.hpp"

namespace dn::hard_cases {

using test::ChannelId;
using test::Format;

constexpr int kW = 32, kH = 16, kN = kW * kH;
// Frames per case: clean up to kBadFrame, the bad one, then clean again.
constexpr int kFrames = 5, kBadFrame = 1;
// The patch that holds the bad value: 8x6 pixels inside the image.
inline bool in_patch(int x, int y) { return x >= 10 && x < 18 && y >= 5 && y < 11; }

// A pipeline as a session opens it: its declared channels, its guides (every
// declared channel that is not the filtered light) and its lights.
struct PipelineKind {
  const char* label;     // test-name part
  const char* pipeline;  // registry name
  std::vector<ChannelId> declared;
  std::vector<ChannelId> guides;
  bool stateless = false;  // no history: the frames after the bad one equal the clean session's
  std::vector<ChannelId> lights = {ChannelId::Radiance};  // the filtered light (radiance_hard_cases_test.cpp)
};

inline const std::vector<PipelineKind>& kinds() {
  using C = ChannelId;
  static const std::vector<PipelineKind> k = {
      {"passthrough", "passthrough", {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion},
       {C::Albedo, C::Normal, C::Depth, C::Motion}, true},
      {"accumulate", "accumulate", {C::Radiance, C::Normal, C::Depth, C::Motion}, {C::Normal, C::Depth, C::Motion}},
      {"svgf", "svgf", {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::Roughness},
       {C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::Roughness}},
      {"svgf_split", "svgf",
       {C::Diffuse, C::Specular, C::SpecularAlbedo, C::Albedo, C::Normal, C::Depth, C::Motion, C::Roughness},
       {C::SpecularAlbedo}, false, {C::Diffuse, C::Specular}},
      {"svgf_fb", "svgf-fb",
       {C::Diffuse, C::Specular, C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion, C::Emission},
       {C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion, C::Emission}, false,
       {C::Diffuse, C::Specular}},
      {"reflect", "reflect",
       {C::Diffuse, C::Specular, C::Emission, C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion,
        C::Position, C::ReflectionPosition, C::ReflectionAlbedo, C::ReflectionNormal, C::ReflectionDepth,
        C::ReflectionDirection, C::ReflectionDistance, C::ReflectionFootprint},
       {C::Emission, C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion, C::Position,
        C::ReflectionPosition, C::ReflectionAlbedo, C::ReflectionNormal, C::ReflectionDepth, C::ReflectionDirection,
        C::ReflectionDistance, C::ReflectionFootprint}, false, {C::Diffuse, C::Specular}},
      {"stat", "stat", {C::Radiance, C::Albedo, C::Normal, C::StatCount, C::StatMean, C::StatM2, C::StatM3},
       {C::Albedo, C::Normal, C::StatCount, C::StatMean, C::StatM2, C::StatM3}, true},
      {"stat_temporal", "stat-temporal",
       {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::StatCount, C::StatMean, C::StatM2, C::StatM3},
       {C::Albedo, C::Normal, C::Depth, C::Motion, C::StatCount, C::StatMean, C::StatM2, C::StatM3}},
      // Without statistics planes: each frame's radiance is one sample.
      {"stat_temporal_radiance", "stat-temporal", {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion},
       {C::Albedo, C::Normal, C::Depth, C::Motion}},
      {"svgf_samples", "svgf",
       {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Sample1Radiance, C::Sample1Normal, C::Sample1Depth,
        C::Sample1Offset},
       {C::Sample1Normal, C::Sample1Depth, C::Sample1Offset}, false, {C::Radiance, C::Sample1Radiance}},
      {"image", "image", {C::Radiance, C::Albedo, C::Normal, C::Depth}, {C::Albedo, C::Normal, C::Depth}, true},
      {"progressive", "progressive",
       {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::SampleCount},
       {C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::SampleCount}},
  };
  return k;
}

// A still camera at the origin looking down -z (fovy 60 degrees), column-major.
constexpr float kTanHalf = 0.57735027f, kAspect = float(kW) / kH, kNear = 0.1f, kFar = 100.0f;
inline std::array<float, 16> identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }
inline std::array<float, 16> projection() {
  std::array<float, 16> m{};
  m[0] = 1.0f / (kTanHalf * kAspect);
  m[5] = 1.0f / kTanHalf;
  m[10] = (kFar + kNear) / (kNear - kFar);
  m[11] = -1.0f;
  m[14] = 2.0f * kFar * kNear / (kNear - kFar);
  return m;
}

// The clean still scene: two surfaces (a plane facing the camera, a tilted
// one on the right), a background corner, smooth light, the three
// reflection classes in columns, a few emitters; statistics of 8 samples
// whose Box-Cox (lambda 1/2) mean gives the radiance back.
inline std::vector<float> clean_plane(ChannelId id, int x, int y) {
  // Light up to 7 (demodulated): 3.4e38 times it overflows where a guide multiplies.
  const float light = 8.0f * (0.4f + 0.3f * std::sin(0.4f * x) * std::cos(0.5f * y) + (x > 20 ? 0.2f : 0.0f));
  const bool background = x < 4 && y < 4;
  const float depth = background ? 0.0f : (x > 20 ? 3.0f + 0.05f * (x - 20) : 2.0f);
  const float nx = x > 20 ? 0.6f : 0.0f, nz = x > 20 ? 0.8f : 1.0f;
  const float px = (2.0f * (x + 0.5f) / kW - 1.0f) * kTanHalf * kAspect * depth;
  const float py = (1.0f - 2.0f * (y + 0.5f) / kH) * kTanHalf * depth;
  const float albedo[3] = {0.3f + 0.02f * (x % 8), 0.5f, 0.7f - 0.03f * (y % 6)};
  switch (id) {
    case ChannelId::Radiance:
    case ChannelId::Sample1Radiance:
    case ChannelId::Diffuse:
      return {albedo[0] * light, albedo[1] * light, albedo[2] * light};
    case ChannelId::Specular: return {0.2f * light, 0.2f * light, 0.2f * light};
    case ChannelId::Albedo: return {albedo[0], albedo[1], albedo[2]};
    case ChannelId::SpecularAlbedo: return {0.4f, 0.4f, 0.4f};
    case ChannelId::SpecularF0: return {0.04f, 0.04f, 0.04f};
    case ChannelId::Roughness: return {x % 3 == 0 ? 0.02f : x % 3 == 1 ? 0.25f : 0.8f};
    case ChannelId::Normal:
    case ChannelId::Sample1Normal: return {nx, 0.0f, nz};
    case ChannelId::Depth:
    case ChannelId::Sample1Depth: return {depth};
    case ChannelId::Sample1Offset: return {0.25f, -0.2f};
    case ChannelId::Motion: return {0.0f, 0.0f};
    case ChannelId::Emission: return (x + 3 * y) % 17 == 0 ? std::vector<float>{0.5f, 0.4f, 0.3f} : std::vector<float>(3, 0.0f);
    case ChannelId::SampleCount: return {1.0f};
    case ChannelId::Position: return {px, py, -depth};
    case ChannelId::ReflectionPosition: return {px, py + 1.0f, -depth - 1.0f};
    case ChannelId::ReflectionAlbedo: return {0.6f, 0.5f, 0.4f};
    case ChannelId::ReflectionNormal: return {0.0f, -0.6f, 0.8f};
    case ChannelId::ReflectionDepth: return {depth + 1.4f};
    case ChannelId::ReflectionDirection: return {0.0f, 0.6f, -0.8f};
    case ChannelId::ReflectionDistance: return {1.4f};
    case ChannelId::ReflectionFootprint: return {0.05f};
    case ChannelId::StatCount: return {8.0f};
    case ChannelId::StatMean: {
      std::vector<float> m;
      for (float a : albedo) m.push_back(2.0f * (std::sqrt(a * light) - 1.0f));
      return m;
    }
    case ChannelId::StatM2: return {0.02f, 0.02f, 0.02f};
    case ChannelId::StatM3: return {0.001f, 0.001f, 0.001f};
    default: throw std::logic_error("no clean plane for this channel");
  }
}

// A plane's format in a session whose planes are `planes`: statistics are fp32 only.
inline Format format_of(ChannelId id, Format planes) {
  const bool statistics = id == ChannelId::StatCount || id == ChannelId::StatMean || id == ChannelId::StatM2 ||
                          id == ChannelId::StatM3;
  return statistics ? Format::F32 : planes;
}

// What the patch holds in a bad frame: component `i` of the plane's values
// inside the patch (counted from 0 in scan order) replacing `clean`.
using Patch = std::function<float(int i, float clean)>;

// A frame of the still scene; with a patch, channel `bad_id` holds the
// patch's values inside the patch.
inline test::HostFrame frame(const PipelineKind& kind, Format planes, bool reset, ChannelId bad_id = ChannelId::Radiance,
                             const Patch& patch = {}) {
  test::HostFrame f;
  f.info.flags = reset ? protocol::kFrameReset : 0u;
  f.info.view = f.info.prev_view = identity();
  f.info.projection = f.info.prev_projection = projection();
  for (ChannelId id : kind.declared) {
    std::vector<float> plane;
    int i = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        for (float v : clean_plane(id, x, y))
          plane.push_back(patch && id == bad_id && in_patch(x, y) ? patch(i++, v) : v);
    f.add(id, format_of(id, planes), plane);
  }
  return f;
}

// With `bad`, channel `bad_id` holds `bad_value` in every component inside the patch.
inline test::HostFrame frame(const PipelineKind& kind, Format planes, bool reset, bool bad, ChannelId bad_id,
                             float bad_value) {
  return bad ? frame(kind, planes, reset, bad_id, [bad_value](int, float) { return bad_value; })
             : frame(kind, planes, reset);
}

inline std::unique_ptr<pipelines::Pipeline> open(const PipelineKind& kind, Format planes, Format output = Format::F32,
                                                 std::vector<pipelines::ParameterValue> params = {}) {
  std::vector<pipelines::InputChannel> channels;
  for (ChannelId id : kind.declared) channels.push_back({id, format_of(id, planes)});
  return pipelines::create(test::context(),
                           test::make_config(kind.pipeline, kW, kH, channels, output, std::move(params)));
}

}  // namespace dn::hard_cases
