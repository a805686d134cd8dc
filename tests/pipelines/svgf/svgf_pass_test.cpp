// svgf one pass at a time: the graph copies every buffer a pass wrote
// (GraphPipeline::set_capture) and each is compared with the same pass of the
// CPU reference, frame after frame, on synthetic inputs and on frames of the
// example path tracer with a moving camera.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <string>

#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "render.hpp"
#include "scenes.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;

class SvgfPassTest : public test::GpuTest {};

constexpr double kTolerance = 1e-3;  // relative RMS, as for the final output

// Captured buffers hold fp32 words.
std::vector<float> as_floats(const std::vector<uint8_t>& bytes) { return test::decode_output(bytes, Format::F32); }

// Components [first, first + count) of each `stride`-float pixel.
std::vector<float> components(const std::vector<float>& v, size_t pixels, int stride, int first, int count) {
  std::vector<float> out;
  out.reserve(pixels * count);
  for (size_t i = 0; i < pixels; ++i)
    for (int k = 0; k < count; ++k) out.push_back(v[i * stride + first + k]);
  return out;
}

// Relative RMS of one captured quantity against the reference's; records the
// worst per quantity for the summary line.
class PassComparison {
 public:
  void check(const std::string& what, const std::vector<float>& got, const std::vector<double>& want) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (size_t i = 0; i < got.size(); ++i) ASSERT_TRUE(std::isfinite(got[i])) << what << " element " << i;
    const double rms = test::relative_rms(got, want);
    EXPECT_LE(rms, kTolerance) << what;
    worst_[what] = std::max(worst_[what], rms);
  }
  void print(const char* name) const {
    std::printf("[ info     ] %s: worst relative RMS per pass:", name);
    for (const auto& [what, rms] : worst_) std::printf(" %s %.2g;", what.c_str(), rms);
    std::printf("\n");
  }

 private:
  std::map<std::string, double> worst_;
};

// Runs `frames` through the device graph with capture on and through the
// reference, comparing after every pass: reproject (temporal colour and
// history length), variance, each a-trous iteration (colour and variance),
// remodulate and the final output (after the TAA blend).
template <typename FrameSource>
void compare_every_pass(gpu::Context& ctx, const char* name, int w, int h, const test::SvgfParams& params,
                        const std::vector<pipelines::ParameterValue>& session_params, int frames, FrameSource source) {
  auto config = svgf_config(w, h, Format::F32, Format::F32, session_params, true);
  ASSERT_FALSE(pipelines::validate(config).has_value());
  auto pipe = pipelines::create(ctx, config);
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  test::SvgfReference ref(w, h, params);
  const size_t n = static_cast<size_t>(w) * h;
  PassComparison cmp;
  for (int t = 0; t < frames; ++t) {
    SCOPED_TRACE(testing::Message() << name << " frame " << t);
    const test::HostFrame f = source(t);
    const std::vector<float> out = run(*pipe, f);
    const std::vector<double> want = ref.step(reference_frame(f, w, h, true));

    const auto reprojected = as_floats(graph->captured("svgf_reproject", "svgf_illum_a"));
    cmp.check("reproject colour", components(reprojected, n, 4, 0, 3), ref.temporal_colour());
    const auto temporal = as_floats(graph->captured("svgf_reproject", "svgf_temporal"));
    cmp.check("reproject length", components(temporal, n, 4, 2, 1), ref.history_length());
    const auto varied = as_floats(graph->captured("svgf_variance", "svgf_illum_a"));
    cmp.check("variance", components(varied, n, 4, 3, 1), ref.variance());
    std::string current = "svgf_illum_a", other = "svgf_illum_b";
    for (int i = 0; i < params.atrous_iterations; ++i) {
      const std::string pass = "svgf_atrous_" + std::to_string(i);
      const auto filtered = as_floats(graph->captured(pass, other));
      std::vector<double> want_rgb, want_var;
      for (size_t p = 0; p < n; ++p) {
        for (int k = 0; k < 3; ++k) want_rgb.push_back(ref.atrous(i)[4 * p + k]);
        want_var.push_back(ref.atrous(i)[4 * p + 3]);
      }
      cmp.check(pass + " colour", components(filtered, n, 4, 0, 3), want_rgb);
      cmp.check(pass + " variance", components(filtered, n, 4, 3, 1), want_var);
      std::swap(current, other);
      if (i == 0) other = "svgf_illum_e";  // a keeps the variance pass's output for the harm guard
    }
    // With the final TAA blend (taa_static_alpha's default) svgf_remodulate
    // writes its colour to the temporal scratch and svgf_taa the Output.
    const bool taa = params.taa_alpha > 0.0 || params.taa_static_alpha > 0.0;
    if (taa)
      cmp.check("remodulate", components(as_floats(graph->captured("svgf_remodulate", "svgf_taa_current")), n, 4, 0, 3),
                ref.remodulated());
    else
      cmp.check("remodulate", as_floats(graph->captured("svgf_remodulate", "output")), ref.remodulated());
    cmp.check("output", out, want);
  }
  cmp.print(name);
}

TEST_F(SvgfPassTest, EveryPassMatchesReferenceOnSyntheticFrames) {
  const int w = 96, h = 64;
  SvgfSceneGen scene(w, h, 777, 1.37f, -0.61f, 0.45f, 0.8f, 0.003);
  compare_every_pass(ctx(), "synthetic", w, h, test::SvgfParams{}, {}, 7, [&](int t) {
    return host_frame(scene.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious,
                      t == 5 ? protocol::kFrameReset : 0u, true);
  });
}

// The paper's configuration (5 iterations, history from the first).
TEST_F(SvgfPassTest, EveryPassMatchesReferenceWithPaperIterations) {
  const int w = 80, h = 48;
  SvgfSceneGen scene(w, h, 99, -0.83f, 0.52f, 0.3f, 0.6f, 0.003);
  test::SvgfParams params;
  params.atrous_iterations = 5;
  params.feedback_tap = 0;
  compare_every_pass(ctx(), "paper", w, h, params, {{"atrous_iterations", 5}, {"feedback_tap", 0}}, 5, [&](int t) {
    return host_frame(scene.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious, 0u, true);
  });
}

// Path-traced frames of the example renderer (scene 1: glossy floor, mirror
// sphere, area light) along its orbiting camera path, 1 spp: real
// disocclusions at object silhouettes, background at infinite depth, exact
// sub-pixel motion.
TEST_F(SvgfPassTest, EveryPassMatchesReferenceOnRenderedFramesWithCameraMotion) {
  const int w = 128, h = 72, scene_id = 1;
  const auto scene = render::build_scene(scene_id);
  render::RenderSettings settings;
  settings.width = w;
  settings.height = h;
  settings.channels.reflection = false;
  compare_every_pass(ctx(), "rendered", w, h, test::SvgfParams{}, {}, 6, [&](int t) {
    // A stride of 4 path frames per denoised frame: about 3.5 px of motion at the edges.
    const int path_frame = 4 * t;
    const render::Camera cam = render::frame_camera(scene_id, path_frame, settings);
    const render::Camera prev = render::frame_camera(scene_id, t == 0 ? path_frame - 1 : path_frame - 4, settings);
    render::FrameBuffers fb = render::render_frame(*scene, cam, prev, t, settings);
    SvgfScene s{fb.radiance, fb.albedo, fb.normal, fb.depth, fb.motion, fb.emission};
    return host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0u, true);
  });
}

TEST_F(SvgfPassTest, CapturingAPassThatDoesNotBindABufferThrows) {
  auto pipe = pipelines::create(ctx(), svgf_config(16, 8));
  auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
  ASSERT_NE(graph, nullptr);
  graph->set_capture(true);
  SvgfSceneGen scene(16, 8, 1, 0.5f, 0.5f, 0.0f, 0.1f);
  run(*pipe, host_frame(scene.frame(0), 16, 8, Format::F32, MotionConvention::PixelsToPrevious, 0u, false));
  EXPECT_THROW(graph->captured("svgf_remodulate", "svgf_aux"), std::out_of_range);
  EXPECT_THROW(graph->captured("no_such_pass", "output"), std::out_of_range);
  EXPECT_NO_THROW(graph->captured("svgf_variance", "svgf_aux"));
}

}  // namespace
}  // namespace dn
