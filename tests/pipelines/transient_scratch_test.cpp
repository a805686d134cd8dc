// Scratch is leased per frame from the device's transient pool and shared by
// sessions between their frames: interleaving two sessions' frames gives each
// exactly the output it gets alone (no pass reads scratch it did not write
// this frame), and the pool holds one session's scratch, not one per session.
#include <gtest/gtest.h>

#include <cstring>

#include "gpu/transient_pool.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;

class TransientScratchTest : public test::GpuTest {};

// The frames of a scene, made once (the generator's noise does not repeat);
// split sessions get a specular plane of their own (a scaled copy of the radiance).
struct Sequence {
  std::vector<std::vector<float>> specular;
  std::vector<test::HostFrame> frames;
  Sequence(SvgfSceneGen scene, int w, int h, int count, bool split) : specular(count) {
    for (int t = 0; t < count; ++t) {
      const SvgfScene s = scene.frame(t);
      specular[t] = s.radiance;
      for (float& v : specular[t]) v *= 0.25f;
      frames.push_back(host_frame(s, w, h, Format::F32, MotionConvention::PixelsToPrevious, 0u, false,
                                  split ? &specular[t] : nullptr));
    }
  }
};

std::vector<std::vector<float>> run_alone(gpu::Context& context, const pipelines::SessionConfig& config,
                                          const Sequence& sequence) {
  auto pipe = pipelines::create(context, config);
  std::vector<std::vector<float>> out;
  for (const auto& f : sequence.frames) out.push_back(run(*pipe, f));
  return out;
}

TEST_F(TransientScratchTest, InterleavedSessionsMatchSessionsRunAlone) {
  const int w = 40, h = 24, frames = 4;
  const auto split = svgf_split_config(w, h, Format::F32, Format::F32, {{"taa_alpha", 0.1}});
  const auto plain = svgf_config(w, h);
  const Sequence seq_a(SvgfSceneGen(w, h, 11, 0.6f, -0.2f, 0.1f, 0.5f, 0.01), w, h, frames, true);
  const Sequence seq_b(SvgfSceneGen(w, h, 12, -0.4f, 0.3f, 0.1f, 0.8f, 0.01), w, h, frames, false);
  const auto alone_a = run_alone(ctx(), split, seq_a);
  const auto alone_b = run_alone(ctx(), plain, seq_b);

  auto a = pipelines::create(ctx(), split);
  auto b = pipelines::create(ctx(), plain);
  ASSERT_GT(a->transient_bytes(), 0u);
  ASSERT_GT(b->transient_bytes(), 0u);
  EXPECT_EQ(a->persistent_bytes() + a->transient_bytes(), a->device_bytes());
  auto& pool = gpu::TransientPool::of(ctx());
  for (int t = 0; t < frames; ++t) {
    const auto fa = run(*a, seq_a.frames[t]);
    const uint64_t allocated = pool.stats().allocated_bytes;
    const auto fb = run(*b, seq_b.frames[t]);
    ASSERT_EQ(fa.size(), alone_a[t].size());
    ASSERT_EQ(fb.size(), alone_b[t].size());
    EXPECT_EQ(0, std::memcmp(fa.data(), alone_a[t].data(), fa.size() * sizeof(float))) << "session a, frame " << t;
    EXPECT_EQ(0, std::memcmp(fb.data(), alone_b[t].data(), fb.size() * sizeof(float))) << "session b, frame " << t;
    // b ran after a returned its scratch: it found what it needed in the pool.
    EXPECT_EQ(pool.stats().allocated_bytes, allocated) << "frame " << t;
    EXPECT_EQ(pool.stats().in_use_bytes, 0u);  // nothing held between frames
  }
}

}  // namespace
}  // namespace dn
