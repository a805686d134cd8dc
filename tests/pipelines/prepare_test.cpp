// prepare() / create(context, prepared): one OPEN_SESSION validates and builds
// its pass graph once; the prepared graph gives the device bytes and the
// pipeline, with the same output as create(context, config).
#include <gtest/gtest.h>

#include <variant>

#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/registry.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;

class PrepareTest : public test::GpuTest {};

TEST_F(PrepareTest, OneSessionBuildsItsGraphOnce) {
  const auto config = svgf_split_config(40, 24, Format::F16, Format::F32, {{"taa_alpha", 0.1}}, true);
  const uint64_t before = pipelines::graphs_built_count();
  auto result = pipelines::prepare(config);
  ASSERT_TRUE(std::holds_alternative<pipelines::PreparedPipeline>(result));
  const auto& prepared = std::get<pipelines::PreparedPipeline>(result);
  const uint64_t bytes = prepared.device_bytes();
  auto pipe = pipelines::create(ctx(), prepared);
  EXPECT_EQ(pipelines::graphs_built_count() - before, 1u);
  EXPECT_EQ(pipe->device_bytes(), bytes);
  EXPECT_EQ(bytes, pipelines::estimate_device_bytes(config));
  EXPECT_EQ(&dynamic_cast<pipelines::GraphPipeline&>(*pipe).spec(), &prepared.graph());  // shared, not copied
}

TEST_F(PrepareTest, PreparedAndConfigPathsGiveTheSameOutput) {
  const int w = 48, h = 32;
  const auto config = svgf_config(w, h, Format::F32, Format::F32, {}, true);
  auto result = pipelines::prepare(config);
  ASSERT_TRUE(std::holds_alternative<pipelines::PreparedPipeline>(result));
  auto prepared = pipelines::create(ctx(), std::get<pipelines::PreparedPipeline>(result));
  auto again = pipelines::create(ctx(), std::get<pipelines::PreparedPipeline>(result));  // reusable
  auto direct = pipelines::create(ctx(), config);
  SvgfSceneGen scene(w, h, 5, 0.7f, -0.3f, 0.2f, 0.5f, 0.01);
  for (int t = 0; t < 3; ++t) {
    const auto f = host_frame(scene.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious, 0u, true);
    const auto a = run(*prepared, f), b = run(*direct, f), c = run(*again, f);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << "frame " << t;
    EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float))) << "frame " << t;
  }
}

TEST(Prepare, ReturnsTheErrorValidateReturns) {
  auto unknown = test::accumulate_config(8, 8);
  unknown.pipeline = "svgf-next";
  auto bad_param = test::accumulate_config(8, 8, Format::F32, Format::F32, {{"max_history", 0.5}});
  auto too_big = test::accumulate_config(16384, 16384);
  for (const auto& config : {unknown, bad_param, too_big}) {
    const auto want = pipelines::validate(config);
    ASSERT_TRUE(want.has_value());
    const auto got = pipelines::prepare(config);
    ASSERT_TRUE(std::holds_alternative<pipelines::ConfigError>(got));
    const auto& err = std::get<pipelines::ConfigError>(got);
    EXPECT_EQ(err.problem, want->problem);
    EXPECT_EQ(err.field, want->field);
    EXPECT_EQ(err.message, want->message);
  }
}

}  // namespace
}  // namespace dn
