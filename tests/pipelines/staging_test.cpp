// The discrete-GPU path on lavapipe: a context whose input and output planes
// go through staging buffers and device copies. Results must be identical to
// the direct-mapped path, with no validation (incl. synchronization) messages.
#include <gtest/gtest.h>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using protocol::MotionConvention;
using test::ChannelId;
using test::Format;

class StagingTest : public test::GpuTest {};

TEST_F(StagingTest, AccumulateAndPassthroughMatchTheDirectPath) {
  gpu::Context& staged = test::staging_context();
  ASSERT_TRUE(staged.force_staging());
  const int w = 45, h = 27;  // odd pixel count
  for (Format in : {Format::F32, Format::F16}) {
    SCOPED_TRACE(in == Format::F16 ? "fp16" : "fp32");
    auto config = test::accumulate_config(w, h, in, in);
    auto direct = pipelines::create(ctx(), config);
    auto staging = pipelines::create(staged, config);
    EXPECT_EQ(direct->device_bytes(), staging->device_bytes());
    auto pass_config = test::make_config("passthrough", w, h, {{ChannelId::Radiance, in}}, in);
    auto pass_direct = pipelines::create(ctx(), pass_config);
    auto pass_staging = pipelines::create(staged, pass_config);

    test::PanningScene scene(w, h, 17, 0.8f, -1.3f, 0.3f, 0.5f);
    for (int t = 0; t < 5; ++t) {
      const test::SceneFrame s = scene.frame(t);
      test::HostFrame f;
      f.info.motion = MotionConvention::PixelsToPrevious;
      f.add(ChannelId::Radiance, in, s.radiance);
      f.add(ChannelId::Normal, in, s.normal);
      f.add(ChannelId::Depth, in, s.depth);
      f.add(ChannelId::Motion, in, s.motion);
      std::vector<uint8_t> a, b;
      std::vector<pipelines::PassTiming> ta, tb;
      test::process(*direct, f.view(), true, a, ta);
      test::process(*staging, f.view(), t != 2, b, tb);  // one frame without download
      if (t != 2) {
        EXPECT_EQ(a, b) << "frame " << t;
      } else {
        EXPECT_TRUE(b.empty());
      }
      ASSERT_EQ(tb.size(), 4u);  // upload, accumulate, sample_summary, download
      ASSERT_TRUE(staging->samples()) << "frame " << t;
      EXPECT_EQ(direct->samples(), staging->samples()) << "frame " << t << ": the summary read back through staging";

      test::HostFrame p;
      p.add(ChannelId::Radiance, in, s.radiance);
      a.clear();
      b.clear();
      test::process(*pass_direct, p.view(), true, a, ta);
      test::process(*pass_staging, p.view(), true, b, tb);
      EXPECT_EQ(a, b) << "passthrough frame " << t;
      EXPECT_EQ(b, p.planes[0].bytes) << "passthrough is not an exact copy";
    }
  }
  expect_no_messages(staged);
}

}  // namespace
}  // namespace dn
