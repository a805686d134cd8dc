// The SVGF chain builder (pipelines/stages/svgf_chain.hpp): variants are data; what
// the shaders do not implement yet is rejected by name; shared resources are
// declared by the pipelines that bind them.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "gpu_test_env.hpp"
#include "pipelines/definitions.hpp"
#include "pipelines/stages/fb_lut.hpp"
#include "pipelines/registry.hpp"
#include "pipelines/stages/svgf_chain.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;
using pipelines::SvgfVariant;

SvgfVariant radiance_variant() {
  SvgfVariant v;
  v.signals.push_back({ChannelId::Radiance, "radiance", "", "svgf", {"albedo", ChannelId::Albedo}});
  return v;
}

std::string rejection(const SvgfVariant& v) {
  try {
    pipelines::check_supported(v);
  } catch (const std::logic_error& e) {
    return e.what();
  }
  return "";
}

TEST(SvgfVariant, WhatTheShadersDoNotImplementIsRejectedByName) {
  EXPECT_EQ(rejection(radiance_variant()), "");
  SvgfVariant v = radiance_variant();
  v.signals[0].motion = pipelines::MotionSource::Reflection;  // without reflect_motion's buffer
  EXPECT_NE(rejection(v).find("reflect_motion buffer"), std::string::npos) << rejection(v);
  v = radiance_variant();
  v.signals[0].features = pipelines::SignalFeatures{"reflect_depth", ""};
  EXPECT_NE(rejection(v).find("depth and a normal buffer"), std::string::npos) << rejection(v);
  v = radiance_variant();
  v.validity_mask = ChannelId::SampleCount;
  EXPECT_EQ(rejection(v), "");
  v.validity_mask = ChannelId::Albedo;
  EXPECT_NE(rejection(v).find("only the sample_count plane"), std::string::npos) << rejection(v);
  v = radiance_variant();
  v.validity_mask = ChannelId::SampleCount;
  v.signals[0].clip = true;
  EXPECT_NE(rejection(v).find("clipped signal"), std::string::npos) << rejection(v);
  v = radiance_variant();
  v.signals[0].modulator = {};
  EXPECT_NE(rejection(v).find("modulator"), std::string::npos) << rejection(v);
  v = radiance_variant();
  v.signals.push_back(v.signals[0]);
  v.signals.push_back(v.signals[0]);
  EXPECT_NE(rejection(v).find("two signals"), std::string::npos) << rejection(v);
}

// Coarse-to-fine steps are data only: iteration i runs step 2^(n-1-i).
pipelines::GraphSpec decreasing_graph(const pipelines::SessionConfig& config) {
  pipelines::GraphSpec g = pipelines::begin_graph(config);
  SvgfVariant v = radiance_variant();
  v.iterations = 3;
  v.feedback_tap = 0;
  v.steps = pipelines::StepOrder::Decreasing;
  pipelines::add_svgf_inputs(g, config, v);
  pipelines::add_svgf_buffers(g, v);
  g.add_output(config);
  pipelines::add_svgf_passes(g, config, v);
  g.size_from_bindings();
  g.check();
  return g;
}

TEST(SvgfVariant, DecreasingStepOrderSpecializesEachIteration) {
  const auto config = svgf_config(40, 24);
  const pipelines::GraphSpec g = decreasing_graph(config);
  std::vector<uint32_t> steps;
  for (const auto& pass : g.passes)
    if (pass.shader() == "svgf_atrous") {
      const auto constants = pass.specialization(64);
      steps.push_back(constants[pass.declaration().constant("STEP")->id].value);
      EXPECT_EQ(constants[pass.declaration().constant("FEEDBACK")->id].value, pass.name() == "svgf_atrous_0" ? 1u : 0u);
    }
  EXPECT_EQ(steps, (std::vector<uint32_t>{4, 2, 1}));
}

// Paper 004's order: the finest step first (it feeds the history), then coarse to fine.
TEST(SvgfVariant, StepOrders) {
  auto steps = [](pipelines::StepOrder order, uint32_t n) {
    std::vector<uint32_t> out;
    for (uint32_t i = 0; i < n; ++i) out.push_back(1u << pipelines::step_level(order, i, n));
    return out;
  };
  EXPECT_EQ(steps(pipelines::StepOrder::FinestFirst, 5), (std::vector<uint32_t>{1, 16, 8, 4, 2}));
  EXPECT_EQ(steps(pipelines::StepOrder::FinestFirst, 6), (std::vector<uint32_t>{1, 32, 16, 8, 4, 2}));
  EXPECT_EQ(steps(pipelines::StepOrder::FinestFirst, 1), (std::vector<uint32_t>{1}));
  EXPECT_EQ(steps(pipelines::StepOrder::Increasing, 4), (std::vector<uint32_t>{1, 2, 4, 8}));
  EXPECT_EQ(steps(pipelines::StepOrder::Decreasing, 3), (std::vector<uint32_t>{4, 2, 1}));
}

// NORMAL_POWER: exact powers of two in phi_normal's range only.
TEST(SvgfVariant, NormalPowerOnlyForExactPowersOfTwo) {
  EXPECT_EQ(pipelines::normal_power_of(1.0f), 0);
  EXPECT_EQ(pipelines::normal_power_of(64.0f), 6);    // progressive's default
  EXPECT_EQ(pipelines::normal_power_of(128.0f), 7);   // svgf's default
  EXPECT_EQ(pipelines::normal_power_of(1024.0f), 10);
  EXPECT_EQ(pipelines::normal_power_of(100.0f), -1);
  EXPECT_EQ(pipelines::normal_power_of(std::nextafter(128.0f, 0.0f)), -1);
  EXPECT_EQ(pipelines::normal_power_of(2048.0f), -1);
  EXPECT_EQ(pipelines::normal_power_of(0.5f), -1);
}

class SvgfVariantDevice : public test::GpuTest {};

TEST_F(SvgfVariantDevice, DecreasingStepOrderRuns) {
  const int w = 40, h = 24;
  const auto config = svgf_config(w, h);
  pipelines::GraphPipeline pipe(ctx(), config, std::make_shared<pipelines::GraphSpec>(decreasing_graph(config)));
  SvgfSceneGen scene(w, h, 3, 0.5f, 0.25f, 0.1f, 0.4f);
  for (int t = 0; t < 3; ++t) {
    const auto out = run(pipe, host_frame(scene.frame(t), w, h, Format::F32, MotionConvention::PixelsToPrevious, 0u,
                                          false));
    for (float v : out) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << v;
  }
}

// svgf-fb declares the F_beta table it binds; the server can make every
// declared resource up front.
TEST_F(SvgfVariantDevice, SharedResourcesAreDeclaredByThePipelinesThatBindThem) {
  const pipelines::PipelineDefinition* fb = pipelines::find_definition("svgf-fb");
  ASSERT_NE(fb, nullptr);
  ASSERT_EQ(fb->shared_resources.size(), 1u);
  EXPECT_EQ(std::string(fb->shared_resources[0].name), "fb_lut");
  EXPECT_TRUE(pipelines::find_definition("svgf")->shared_resources.empty());
  pipelines::prepare_shared_resources(ctx());
  EXPECT_EQ(&fb->shared_resources[0].resource(ctx()), &pipelines::fb_lut(ctx()).buffer());
  const auto graph = fb->build(test::make_config(
      "svgf-fb", 8, 8,
      {{ChannelId::Diffuse, Format::F32}, {ChannelId::Specular, Format::F32}, {ChannelId::Albedo, Format::F32},
       {ChannelId::SpecularF0, Format::F32}, {ChannelId::Roughness, Format::F32}, {ChannelId::Normal, Format::F32},
       {ChannelId::Depth, Format::F32}, {ChannelId::Motion, Format::F32}}));
  const auto* lut = graph.find("fb_lut");
  ASSERT_NE(lut, nullptr);
  EXPECT_EQ(lut->role, pipelines::BufferRole::Shared);
  EXPECT_EQ(lut->shared, fb->shared_resources[0].resource);
}

}  // namespace
}  // namespace dn
