// svgf-fb on the device: the F_beta factor pass and the whole pipeline
// against the CPU reference (svgf_reference.cpp with the specular divided by
// F_beta), the L_W input path, and its hard cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "camera.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/stages/fb_lut.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/sample_summary.hpp"
#include "render.hpp"
#include "scenes.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;

class SvgfFbTest : public test::GpuTest {};

// One frame of every channel svgf-fb takes, plus its camera.
struct FbFrame {
  int w = 0, h = 0;
  std::vector<float> diffuse, specular, albedo, f0, roughness, normal, depth, motion, emission;
  glm::mat4 view{1.0f}, projection{1.0f};
};

std::array<float, 16> to_array(const glm::mat4& m) {
  std::array<float, 16> a{};
  std::memcpy(a.data(), &m[0][0], sizeof a);
  return a;
}

pipelines::SessionConfig fb_config(int w, int h, std::vector<pipelines::ParameterValue> params = {},
                                   const std::string& pipeline = "svgf-fb") {
  std::vector<pipelines::InputChannel> channels = {
      {ChannelId::Diffuse, Format::F32}, {ChannelId::Specular, Format::F32}, {ChannelId::Albedo, Format::F32},
      {ChannelId::Normal, Format::F32},  {ChannelId::Depth, Format::F32},    {ChannelId::Motion, Format::F32},
      {ChannelId::Emission, Format::F32}};
  if (pipeline == "svgf-fb") {
    channels.push_back({ChannelId::SpecularF0, Format::F32});
    channels.push_back({ChannelId::Roughness, Format::F32});
  }
  return test::make_config(pipeline, w, h, channels, Format::F32, std::move(params));
}

test::HostFrame host(const FbFrame& f, bool reset) {
  test::HostFrame h;
  h.info.flags = reset ? protocol::kFrameReset : 0u;
  h.info.view = to_array(f.view);
  h.info.projection = to_array(f.projection);
  h.add(ChannelId::Diffuse, Format::F32, f.diffuse);
  h.add(ChannelId::Specular, Format::F32, f.specular);
  h.add(ChannelId::Albedo, Format::F32, f.albedo);
  h.add(ChannelId::Normal, Format::F32, f.normal);
  h.add(ChannelId::Depth, Format::F32, f.depth);
  h.add(ChannelId::Motion, Format::F32, f.motion);
  h.add(ChannelId::Emission, Format::F32, f.emission);
  h.add(ChannelId::SpecularF0, Format::F32, f.f0);
  h.add(ChannelId::Roughness, Format::F32, f.roughness);
  return h;
}

// Path-traced frames of dnrender scene 1 (roughness-mapped coated floor,
// metal spheres) along its orbit, 1 spp; `still`: the camera holds its first
// position (zero motion: history clipping's static rule).
class RenderedFrames {
 public:
  RenderedFrames(int w, int h, bool still = false) : scene_(render::build_scene(1)), still_(still) {
    settings_.width = w;
    settings_.height = h;
  }
  FbFrame frame(int t) {
    const int path = still_ ? 0 : 3 * t;
    const render::Camera cam = render::frame_camera(1, path, settings_);
    const render::Camera prev = render::frame_camera(1, still_ ? path : t == 0 ? path - 1 : path - 3, settings_);
    render::FrameBuffers fb = render::render_frame(*scene_, cam, prev, t, settings_);
    return FbFrame{fb.width,      fb.height, fb.diffuse, fb.specular, fb.albedo, fb.specular_f0, fb.roughness,
                   fb.normal,     fb.depth,  fb.motion,  fb.emission, cam.view,  cam.projection};
  }

 private:
  std::unique_ptr<render::Scene> scene_;
  bool still_;
  render::RenderSettings settings_;
};

// Host F_beta per pixel, written from the rules in docs/pipelines.md
// ("svgf-fb"): cos theta_o from the renderer's camera rays, the table read
// back from the device, bilinear between texel centres.
class HostFactor {
 public:
  explicit HostFactor(gpu::Context& ctx) : table_(pipelines::fb_lut(ctx).read()) {}

  double lut(double cos_o, double alpha, int component) const {
    const int n = static_cast<int>(pipelines::kFbLutSize);
    auto axis = [&](double v, int& i0, int& i1, double& t) {
      const double u = std::clamp(v * n - 0.5, 0.0, n - 1.0);
      i0 = static_cast<int>(std::floor(u));
      i1 = std::min(i0 + 1, n - 1);
      t = u - i0;
    };
    int c0, c1, a0, a1;
    double tc, ta;
    axis(cos_o, c0, c1, tc);
    axis(alpha, a0, a1, ta);
    auto at = [&](int a, int c) { return static_cast<double>(table_[2 * (a * n + c) + component]); };
    return (1 - ta) * ((1 - tc) * at(a0, c0) + tc * at(a0, c1)) + ta * ((1 - tc) * at(a1, c0) + tc * at(a1, c1));
  }

  std::vector<double> factor(const FbFrame& f) const {
    // The view ray of the example renderer's own camera code, not a copy of the shader's unprojection.
    const render::CameraRays rays(render::Camera{f.view, f.projection, glm::vec2(0.0f)}, f.w, f.h);
    std::vector<double> out(3 * f.w * f.h, 1.0);
    for (int y = 0; y < f.h; ++y)
      for (int x = 0; x < f.w; ++x) {
        const int i = y * f.w + x;
        const double z = f.depth[i];
        if (!(std::isfinite(z) && z > 0.0)) continue;
        const glm::dvec3 ray(rays.direction(x + 0.5f, y + 0.5f));
        glm::dvec3 n(f.normal[3 * i], f.normal[3 * i + 1], f.normal[3 * i + 2]);
        const double len = glm::length(n);
        const double cos_o = len > 0.0 ? std::clamp(-glm::dot(n, ray) / len, 0.0, 1.0) : 0.0;
        const double alpha = std::clamp(static_cast<double>(f.roughness[i]), 0.0, 1.0);
        const double a = lut(cos_o, alpha, 0), b = lut(cos_o, alpha, 1);
        for (int k = 0; k < 3; ++k) out[3 * i + k] = std::clamp(static_cast<double>(f.f0[3 * i + k]), 0.0, 1.0) * a + b;
      }
    return out;
  }

 private:
  std::vector<float> table_;
};

test::SvgfFrame reference_input(const FbFrame& f, bool reset, const std::vector<double>& factor) {
  auto d = [](const std::vector<float>& v) { return std::vector<double>(v.begin(), v.end()); };
  test::SvgfFrame r;
  r.diffuse = d(f.diffuse);
  r.specular = d(f.specular);
  r.albedo = d(f.albedo);
  r.normal = d(f.normal);
  r.depth = d(f.depth);
  r.motion = d(f.motion);
  r.emission = d(f.emission);
  r.specular_factor = factor;
  r.roughness = d(f.roughness);
  r.reset = reset;
  return r;
}

// Captured buffers hold fp32 words.
std::vector<float> as_floats(const std::vector<uint8_t>& bytes) { return test::decode_output(bytes, Format::F32); }

void expect_matches_cpu_reference(gpu::Context& ctx, bool still, int frame_count) {
  const int w = 96, h = 54;
  auto pipe = pipelines::create(ctx, fb_config(w, h));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  const HostFactor host_factor(ctx);
  test::SvgfReference ref(w, h, test::SvgfParams{});
  RenderedFrames frames(w, h, still);
  double worst_factor = 0.0, worst_output = 0.0;
  for (int t = 0; t < frame_count; ++t) {
    SCOPED_TRACE(testing::Message() << "frame " << t);
    const FbFrame f = frames.frame(t);
    const auto factor = host_factor.factor(f);
    const auto got = run(*pipe, host(f, t == 0));
    const auto want = ref.step(reference_input(f, t == 0, factor));
    for (float g : got) ASSERT_TRUE(std::isfinite(g) && g >= 0.0f) << g;
    const auto device_factor = as_floats(graph->captured("svgf_fb_factor", "svgf_fb"));
    const double rf = test::relative_rms(device_factor, factor), ro = test::relative_rms(got, want);
    EXPECT_LE(rf, 1e-4) << "F_beta factor";
    EXPECT_LE(ro, 1e-3) << "output";
    worst_factor = std::max(worst_factor, rf);
    worst_output = std::max(worst_output, ro);
  }
  std::printf("[ info     ] svgf-fb vs CPU reference, %s camera: factor %.2g, output %.2g (worst relative RMS over %d "
              "frames)\n",
              still ? "still" : "moving", worst_factor, worst_output, frame_count);
}

TEST_F(SvgfFbTest, MatchesCpuReferenceOnRenderedFrames) { expect_matches_cpu_reference(ctx(), false, 5); }

// A still camera: the histories grow long, the rejection reads its 3x3
// history sigma and the clip box is widened by it (static pixels).
TEST_F(SvgfFbTest, MatchesCpuReferenceOnAStillCamera) { expect_matches_cpu_reference(ctx(), true, 8); }

// Paper 000 Eq. 11: a renderer that computes F_beta itself sends
// L_W = specular / F_beta (same floor) as specular_lighting with F_beta as
// specular_albedo, to svgf (the lighting form, docs/protocol.md §7.4), and
// gets svgf-fb's output.
TEST_F(SvgfFbTest, LightingFormAgreesWithServerDemodulation) {
  const int w = 80, h = 45;
  auto server_side = pipelines::create(ctx(), fb_config(w, h));
  // svgf-fb's channels with the specular part in the lighting form, without F0.
  auto lighting_config = fb_config(w, h);
  std::erase_if(lighting_config.channels, [](const auto& c) { return c.id == ChannelId::SpecularF0; });
  for (auto& c : lighting_config.channels)
    if (c.id == ChannelId::Specular) c.id = ChannelId::SpecularLighting;
  lighting_config.channels.push_back({ChannelId::SpecularAlbedo, Format::F32});
  lighting_config.pipeline = "svgf";
  auto client_side = pipelines::create(ctx(), lighting_config);
  const HostFactor host_factor(ctx());
  RenderedFrames frames(w, h);
  double worst = 0.0;
  for (int t = 0; t < 4; ++t) {
    const FbFrame f = frames.frame(t);
    const auto factor = host_factor.factor(f);
    std::vector<float> lw(f.specular.size()), fb(f.specular.size());
    for (size_t i = 0; i < lw.size(); ++i) {
      const double g = factor[i] >= static_cast<double>(1e-3f) ? factor[i] : 1.0;
      lw[i] = static_cast<float>(f.specular[i] / g);
      fb[i] = static_cast<float>(factor[i]);
    }
    test::HostFrame lighting = host(f, t == 0);
    std::erase_if(lighting.planes, [](const auto& p) {
      return p.id == ChannelId::Specular || p.id == ChannelId::SpecularF0;
    });
    lighting.add(ChannelId::SpecularLighting, Format::F32, lw);
    lighting.add(ChannelId::SpecularAlbedo, Format::F32, fb);
    const auto a = run(*server_side, host(f, t == 0));
    const auto b = run(*client_side, lighting);
    std::vector<double> ad(a.begin(), a.end());
    const double rms = test::relative_rms(b, ad);
    worst = std::max(worst, rms);
    EXPECT_LE(rms, 1e-4) << "frame " << t;
  }
  std::printf("[ info     ] lighting form vs server demodulation: worst relative RMS %.2g\n", worst);
}

// F0 = 0 and no specular light (a purely diffuse scene): svgf-fb is svgf's split mode exactly.
TEST_F(SvgfFbTest, PureDiffuseIsSvgf) {
  const int w = 64, h = 36;
  auto fb = pipelines::create(ctx(), fb_config(w, h));
  auto svgf = pipelines::create(ctx(), fb_config(w, h, {}, "svgf"));
  RenderedFrames frames(w, h);
  for (int t = 0; t < 4; ++t) {
    FbFrame f = frames.frame(t);
    std::fill(f.f0.begin(), f.f0.end(), 0.0f);
    std::fill(f.specular.begin(), f.specular.end(), 0.0f);
    test::HostFrame plain = host(f, t == 0);
    plain.planes.erase(plain.planes.end() - 2, plain.planes.end());  // svgf takes no F0 / roughness
    EXPECT_EQ(run(*fb, host(f, t == 0)), run(*svgf, plain)) << "frame " << t;
  }
}

// Mirrors (alpha 0 and 1e-4), rough surfaces, normals from head-on to
// perpendicular to the view and past it (cos theta_o = 0), F0 from 0 to 1.
// The factor pass must match the host computation there; without the spatial
// filter (atrous_iterations = 0) a constant input comes back exactly (divide
// and multiply by the same F_beta); with it, the output stays finite and
// within the input's range (the filter mixes neighbours' L_W, which differ
// because F_beta does).
TEST_F(SvgfFbTest, MirrorsAndGrazingNormals) {
  const int w = 64, h = 40, n = w * h;
  FbFrame f;
  f.w = w;
  f.h = h;
  f.view = glm::lookAt(glm::vec3(0, 0, 3), glm::vec3(0, 0, 0), glm::vec3(0, 1, 0));
  f.projection = glm::perspective(glm::radians(60.0f), float(w) / h, 0.1f, 100.0f);
  f.diffuse.assign(3 * n, 0.3f);
  f.specular.resize(3 * n);
  f.albedo.assign(3 * n, 0.5f);
  f.f0.resize(3 * n);
  f.roughness.resize(n);
  f.normal.assign(3 * n, 0.0f);
  f.depth.assign(n, 3.0f);
  f.motion.assign(2 * n, 0.0f);
  f.emission.assign(3 * n, 0.0f);
  const float alphas[] = {0.0f, 1e-4f, 0.05f, 0.5f, 1.0f};
  for (int i = 0; i < n; ++i) {
    const int x = i % w, y = i / w;
    const float tilt = 1.75f * x / (w - 1);  // radians: from facing the camera to past perpendicular
    f.normal[3 * i] = std::sin(tilt);
    f.normal[3 * i + 2] = std::cos(tilt);
    f.roughness[i] = alphas[(y / 8) % 5];
    for (int k = 0; k < 3; ++k) {
      f.f0[3 * i + k] = k == 0 ? 1.0f : (k == 1 ? 0.04f : 0.0f);
      f.specular[3 * i + k] = 0.2f + 0.1f * k;
    }
  }
  const HostFactor host_factor(ctx());
  const auto factor = host_factor.factor(f);
  for (double v : factor) ASSERT_TRUE(std::isfinite(v) && v >= 0.0 && v <= 1.0 + 1e-3) << v;  // A + B <= 1 up to the table's sampling noise

  auto temporal_only = pipelines::create(ctx(), fb_config(w, h, {{"atrous_iterations", 0}, {"clip_roughness", 0}}));
  // History clipping off: its box decisions are not part of what this test
  // checks (the F_beta guards), and they would change a constant L_W's history.
  auto full = pipelines::create(ctx(), fb_config(w, h, {{"clip_roughness", 0}}));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(full.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  for (int t = 0; t < 4; ++t) {
    const auto exact = run(*temporal_only, host(f, t == 0));
    const auto filtered = run(*full, host(f, t == 0));
    EXPECT_LE(test::relative_rms(as_floats(graph->captured("svgf_fb_factor", "svgf_fb")), factor), 1e-4);
    for (int i = 0; i < 3 * n; ++i) {
      const float want = f.diffuse[i] + f.specular[i];  // both are radiance; albedo and F_beta cancel
      ASSERT_NEAR(exact[i], want, 1e-5f * want) << "frame " << t << " element " << i;
      ASSERT_TRUE(std::isfinite(filtered[i]) && filtered[i] >= 0.0f) << filtered[i];
    }
  }
}

TEST_F(SvgfFbTest, OutputScalesWithInput) {
  const int w = 64, h = 36;
  RenderedFrames frames(w, h);
  std::vector<FbFrame> seq;
  for (int t = 0; t < 4; ++t) seq.push_back(frames.frame(t));
  std::vector<std::vector<float>> base;
  {
    auto pipe = pipelines::create(ctx(), fb_config(w, h));
    for (int t = 0; t < 4; ++t) base.push_back(run(*pipe, host(seq[t], t == 0)));
  }
  for (double k : {1e-6, 1e-3, 1e3, 1e4}) {
    auto pipe = pipelines::create(ctx(), fb_config(w, h));
    double worst = 0.0;
    for (int t = 0; t < 4; ++t) {
      FbFrame f = seq[t];
      for (auto* v : {&f.diffuse, &f.specular, &f.emission})
        for (auto& x : *v) x = static_cast<float>(x * k);
      const auto out = run(*pipe, host(f, t == 0));
      std::vector<float> got(out.size());
      std::vector<double> want(out.size());
      for (size_t i = 0; i < out.size(); ++i) {
        got[i] = static_cast<float>(out[i] / k);
        want[i] = base[t][i];
      }
      worst = std::max(worst, test::relative_rms(got, want));
    }
    std::printf("[ info     ] svgf-fb k = %g: worst relative RMS %.2g\n", k, worst);
    EXPECT_LE(worst, 1e-3) << "k = " << k;
  }
}

TEST(SvgfFbValidate, RequiresF0AndRoughnessAndSplitLighting) {
  EXPECT_FALSE(pipelines::validate(fb_config(32, 16)).has_value());
  for (ChannelId missing : {ChannelId::SpecularF0, ChannelId::Roughness, ChannelId::Specular}) {
    auto c = fb_config(32, 16);
    std::erase_if(c.channels, [&](const pipelines::InputChannel& d) { return d.id == missing; });
    const auto err = pipelines::validate(c);
    ASSERT_TRUE(err.has_value());
    EXPECT_NE(err->message.find(protocol::find_channel(missing)->name), std::string::npos) << err->message;
  }
  auto radiance = fb_config(32, 16);
  radiance.channels.push_back({ChannelId::Radiance, Format::F32});
  EXPECT_TRUE(pipelines::validate(radiance).has_value());
}

// Split mode's 368 B/px (fp32, no emission, with the TAA history and the
// still means) + emission 12 and its still mean 16 + 8 + F0 12 + roughness 4
// + the F_beta factor scratch 12 + history clipping's three scratch buffers
// 3 x 16 = 480 B/px; the table itself is the context's.
TEST_F(SvgfFbTest, DeviceBytesAreAsDocumented) {
  const auto config = fb_config(64, 48);
  EXPECT_EQ(pipelines::estimate_device_bytes(config), 64u * 48 * 480 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  EXPECT_EQ(pipelines::create(ctx(), config)->device_bytes(), pipelines::estimate_device_bytes(config));
}

}  // namespace
}  // namespace dn
