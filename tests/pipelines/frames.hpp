// Test helpers: building sessions and frames, encoding planes, decoding output.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

#include "dn/protocol/channels.hpp"
#include "dn/protocol/messages.hpp"
#include "half.hpp"
#include "session/frame_planes.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::test {

using protocol::ChannelId;
using protocol::Format;

inline std::vector<uint8_t> encode_plane(const std::vector<float>& values, Format format) {
  std::vector<uint8_t> out(values.size() * protocol::bytes_per_component(format));
  if (format == Format::F32) {
    std::memcpy(out.data(), values.data(), out.size());
  } else {
    for (size_t i = 0; i < values.size(); ++i) {
      const uint16_t h = to_half(values[i]);
      std::memcpy(out.data() + 2 * i, &h, 2);
    }
  }
  return out;
}

// The values the device sees for a plane (fp16 decoded exactly).
inline std::vector<double> decode_plane(const std::vector<uint8_t>& bytes, Format format) {
  std::vector<double> out(bytes.size() / protocol::bytes_per_component(format));
  for (size_t i = 0; i < out.size(); ++i) {
    if (format == Format::F32) {
      float f;
      std::memcpy(&f, bytes.data() + 4 * i, 4);
      out[i] = f;
    } else {
      uint16_t h;
      std::memcpy(&h, bytes.data() + 2 * i, 2);
      out[i] = from_half(h);
    }
  }
  return out;
}

struct HostPlane {
  ChannelId id;
  Format format;
  std::vector<uint8_t> bytes;
};

struct HostFrame {
  protocol::FrameInfo info;
  std::vector<HostPlane> planes;

  void add(ChannelId id, Format format, const std::vector<float>& values) {
    planes.push_back({id, format, encode_plane(values, format)});
  }
  const HostPlane& plane(ChannelId id) const {
    for (const auto& p : planes)
      if (p.id == id) return p;
    throw std::logic_error("no such plane");
  }
  protocol::Frame view() const {
    protocol::Frame f;
    f.info = info;
    for (const auto& p : planes) f.planes.push_back({p.id, p.format, p.bytes});
    return f;
  }
};

// Runs `frame` through `pipeline` as a session does: its planes checked by
// frame_input() (std::invalid_argument when they do not fit the session).
inline void process(pipelines::Pipeline& pipeline, const protocol::Frame& frame, bool want_output,
                    std::vector<uint8_t>& output, std::vector<pipelines::PassTiming>& timings) {
  pipeline.process(server::frame_planes_or_throw(frame, pipeline.config()), want_output, output, timings);
}

inline pipelines::SessionConfig make_config(const std::string& pipeline, uint32_t w, uint32_t h,
                                            std::vector<pipelines::InputChannel> channels,
                                            Format output = Format::F32,
                                            std::vector<pipelines::ParameterValue> parameters = {}) {
  pipelines::SessionConfig c;
  c.pipeline = pipeline;
  c.width = w;
  c.height = h;
  c.output_format = output;
  c.channels = std::move(channels);
  c.parameters = std::move(parameters);
  return c;
}

inline pipelines::SessionConfig accumulate_config(uint32_t w, uint32_t h, Format inputs = Format::F32,
                                                  Format output = Format::F32,
                                                  std::vector<pipelines::ParameterValue> parameters = {}) {
  return make_config("accumulate", w, h,
                     {{ChannelId::Radiance, inputs}, {ChannelId::Normal, inputs}, {ChannelId::Depth, inputs},
                      {ChannelId::Motion, inputs}},
                     output, std::move(parameters));
}

inline std::vector<float> decode_output(const std::vector<uint8_t>& bytes, Format format) {
  std::vector<float> out;
  for (double v : decode_plane(bytes, format)) out.push_back(static_cast<float>(v));
  return out;
}

// sqrt(sum (a - b)^2 / sum b^2)
inline double relative_rms(const std::vector<float>& got, const std::vector<double>& want) {
  double num = 0, den = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    num += (got[i] - want[i]) * (got[i] - want[i]);
    den += want[i] * want[i];
  }
  return std::sqrt(num / std::max(den, 1e-300));
}

// Screen-space scene seen by a panning camera: tiles of three surfaces
// (distinct depths and normals, so reprojection either clearly accepts or
// clearly rejects) and background tiles (depth 0 or +inf). Motion vectors
// are the camera motion plus per-pixel noise, in pixels to the previous frame.
struct SceneFrame {
  std::vector<float> radiance, normal, depth, motion;
};

class PanningScene {
 public:
  PanningScene(int w, int h, uint32_t seed, float vx, float vy, float motion_noise, float radiance_noise,
               double special_fraction = 0.0)
      : w_(w), h_(h), rng_(seed), vx_(vx), vy_(vy), motion_noise_(motion_noise), radiance_noise_(radiance_noise),
        special_fraction_(special_fraction) {}

  SceneFrame frame(int t) {
    SceneFrame f;
    const int n = w_ * h_;
    f.radiance.resize(3 * n);
    f.normal.resize(3 * n);
    f.depth.resize(n);
    f.motion.resize(2 * n);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int y = 0; y < h_; ++y) {
      for (int x = 0; x < w_; ++x) {
        const int i = y * w_ + x;
        const double u = x + 0.5 + vx_ * t, v = y + 0.5 + vy_ * t;  // world position of the pixel centre
        const int cx = static_cast<int>(std::floor(u / 23.0)), cy = static_cast<int>(std::floor(v / 17.0));
        const uint32_t hash = static_cast<uint32_t>(cx) * 73856093u ^ static_cast<uint32_t>(cy) * 19349663u;
        const int type = static_cast<int>(hash % 5u);
        float albedo[3] = {0.5f, 0.5f, 0.5f};
        float nrm[3] = {0, 0, 1};
        float z = 0.0f;
        switch (type) {
          case 0: z = 0.0f; break;
          case 1: z = INFINITY; break;
          case 2: z = static_cast<float>(2.0 + 0.002 * u); albedo[0] = 0.9f; albedo[1] = 0.4f; albedo[2] = 0.2f; break;
          case 3:
            z = static_cast<float>(5.0 + 0.003 * v);
            nrm[0] = 0.6f; nrm[2] = 0.8f;
            albedo[0] = 0.2f; albedo[1] = 0.7f; albedo[2] = 0.3f;
            break;
          default:
            z = 1.2f;
            nrm[1] = 0.8f; nrm[2] = 0.6f;
            albedo[0] = 0.3f; albedo[1] = 0.3f; albedo[2] = 0.9f;
            break;
        }
        const double pattern = 1.0 + 0.5 * std::sin(0.21 * u) * std::cos(0.17 * v);
        for (int k = 0; k < 3; ++k)
          f.radiance[3 * i + k] = static_cast<float>(albedo[k] * pattern * (1.0 + radiance_noise_ * (2 * unit(rng_) - 1)));
        for (int k = 0; k < 3; ++k) f.normal[3 * i + k] = nrm[k];
        f.depth[i] = z;
        f.motion[2 * i] = vx_ + motion_noise_ * (2 * unit(rng_) - 1);
        f.motion[2 * i + 1] = vy_ + motion_noise_ * (2 * unit(rng_) - 1);
        if (special_fraction_ > 0 && unit(rng_) < special_fraction_) {
          const float specials[] = {NAN, INFINITY, -INFINITY, -1.0f, -1e30f};
          f.radiance[3 * i + (i % 3)] = specials[static_cast<uint32_t>(unit(rng_) * 5) % 5];
        }
      }
    }
    return f;
  }

 private:
  int w_, h_;
  std::mt19937 rng_;
  float vx_, vy_, motion_noise_, radiance_noise_;
  double special_fraction_;
};

}  // namespace dn::test
