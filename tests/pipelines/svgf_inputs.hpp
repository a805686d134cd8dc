// Inputs shared by the svgf tests: session configs, a synthetic moving scene
// with albedo and emission, and the conversion of a frame to the CPU
// reference's form.
#pragma once

#include <cmath>
#include <vector>

#include "frames.hpp"
#include "pipelines/pipeline.hpp"
#include "svgf_reference.hpp"

namespace dn::svgf_inputs {

using protocol::MotionConvention;
using test::ChannelId;
using test::Format;

inline pipelines::SessionConfig svgf_config(int w, int h, Format in = Format::F32, Format out = Format::F32,
                                     std::vector<pipelines::ParameterValue> params = {}, bool emission = false) {
  std::vector<pipelines::InputChannel> channels = {{ChannelId::Radiance, in}, {ChannelId::Albedo, in},
                                                 {ChannelId::Normal, in},   {ChannelId::Depth, in},
                                                 {ChannelId::Motion, in}};
  if (emission) channels.push_back({ChannelId::Emission, in});
  return test::make_config("svgf", w, h, channels, out, std::move(params));
}

// Split mode: Diffuse + Specular instead of Radiance.
inline pipelines::SessionConfig svgf_split_config(int w, int h, Format in = Format::F32, Format out = Format::F32,
                                           std::vector<pipelines::ParameterValue> params = {}, bool emission = false) {
  auto c = svgf_config(w, h, in, out, std::move(params), emission);
  c.channels[0] = {ChannelId::Diffuse, in};
  c.channels.insert(c.channels.begin() + 1, {ChannelId::Specular, in});
  return c;
}

struct SvgfScene {
  std::vector<float> radiance, albedo, normal, depth, motion, emission;
};

// A panning camera over tiled surfaces (test::PanningScene) plus an albedo
// that follows the world (some channels below the 1e-3 guard, some exactly 0,
// some tiles no reflectance: all 0, or one component 3) and a few emissive tiles.
class SvgfSceneGen {
 public:
  SvgfSceneGen(int w, int h, uint32_t seed, float vx, float vy, float motion_noise, float radiance_noise,
               double special_fraction = 0.0)
      : w_(w), h_(h), vx_(vx), vy_(vy), scene_(w, h, seed, vx, vy, motion_noise, radiance_noise, special_fraction) {}

  SvgfScene frame(int t) {
    test::SceneFrame s = scene_.frame(t);
    SvgfScene f{s.radiance, {}, s.normal, s.depth, s.motion, {}};
    f.albedo.resize(3 * w_ * h_);
    f.emission.assign(3 * w_ * h_, 0.0f);
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        const int i = y * w_ + x;
        const double u = x + 0.5 + vx_ * t, v = y + 0.5 + vy_ * t;
        const int cx = static_cast<int>(std::floor(u / 11.0)), cy = static_cast<int>(std::floor(v / 9.0));
        const uint32_t hash = static_cast<uint32_t>(cx) * 2654435761u ^ static_cast<uint32_t>(cy) * 40503u;
        for (int k = 0; k < 3; ++k) f.albedo[3 * i + k] = 0.1f + 0.8f * static_cast<float>((hash >> (4 * k)) % 16) / 15.0f;
        if (hash % 7 == 0) f.albedo[3 * i + 1] = 0.0f;
        if (hash % 11 == 0) f.albedo[3 * i + 2] = 5e-4f;
        // Albedos that are no reflectance (keep_unexplained): 0 (a mirror under a diffuse colour), 3.
        if (hash % 17 == 0)
          for (int k = 0; k < 3; ++k) f.albedo[3 * i + k] = 0.0f;
        if (hash % 19 == 0) f.albedo[3 * i] = 3.0f;
        if (hash % 13 == 0)
          for (int k = 0; k < 3; ++k) f.emission[3 * i + k] = 2.0f + k;
      }
    return f;
  }

 private:
  int w_, h_;
  float vx_, vy_;
  test::PanningScene scene_;
};

// specular non-null: split mode, s.radiance is sent as Diffuse and *specular as Specular.
inline test::HostFrame host_frame(const SvgfScene& s, int w, int h, Format in, MotionConvention conv, uint32_t flags,
                           bool emission, const std::vector<float>* specular = nullptr) {
  test::HostFrame f;
  f.info.flags = flags;
  f.info.motion = conv;
  std::vector<float> mv = s.motion;
  for (size_t i = 0; i < mv.size(); ++i) {
    if (conv == MotionConvention::PixelsToNext) mv[i] = -mv[i];
    if (conv == MotionConvention::UvToPrevious) mv[i] /= static_cast<float>(i % 2 == 0 ? w : h);
  }
  if (specular) {
    f.add(ChannelId::Diffuse, in, s.radiance);
    f.add(ChannelId::Specular, in, *specular);
  } else {
    f.add(ChannelId::Radiance, in, s.radiance);
  }
  f.add(ChannelId::Albedo, in, s.albedo);
  f.add(ChannelId::Normal, in, s.normal);
  f.add(ChannelId::Depth, in, s.depth);
  f.add(ChannelId::Motion, in, mv);
  if (emission) f.add(ChannelId::Emission, in, s.emission);
  return f;
}

inline test::SvgfFrame reference_frame(const test::HostFrame& f, int w, int h, bool emission, bool split = false) {
  auto plane = [&](ChannelId id) { return test::decode_plane(f.plane(id).bytes, f.plane(id).format); };
  test::SvgfFrame r;
  if (split) {
    r.diffuse = plane(ChannelId::Diffuse);
    r.specular = plane(ChannelId::Specular);
  } else {
    r.radiance = plane(ChannelId::Radiance);
  }
  r.albedo = plane(ChannelId::Albedo);
  r.normal = plane(ChannelId::Normal);
  r.depth = plane(ChannelId::Depth);
  r.motion = plane(ChannelId::Motion);
  if (emission) r.emission = plane(ChannelId::Emission);
  for (size_t i = 0; i < r.motion.size(); ++i) {
    if (f.info.motion == MotionConvention::PixelsToNext) r.motion[i] = -r.motion[i];
    if (f.info.motion == MotionConvention::UvToPrevious) r.motion[i] *= (i % 2 == 0 ? w : h);
  }
  r.reset = (f.info.flags & protocol::kFrameReset) != 0;
  return r;
}

inline std::vector<float> run(pipelines::Pipeline& p, const test::HostFrame& f, Format out = Format::F32,
                       std::vector<pipelines::PassTiming>* timings = nullptr) {
  std::vector<uint8_t> bytes;
  std::vector<pipelines::PassTiming> t;
  test::process(p, f.view(), true, bytes, timings ? *timings : t);
  return test::decode_output(bytes, out);
}

}  // namespace dn::svgf_inputs
