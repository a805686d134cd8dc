// Building graphs by name (pipelines/pass.hpp, GraphSpec::check): every name
// a builder uses must exist in the shader's declaration, every required
// binding must be bound, and specializations are canonical. No device.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "frames.hpp"
#include "pipelines/definitions.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/input_forms.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

pipelines::GraphSpec passthrough_graph() {
  pipelines::GraphSpec g;
  g.width = 4;
  g.height = 2;
  const auto config = test::make_config("passthrough", 4, 2, {{ChannelId::Radiance, Format::F32}});
  g.add_input(config, ChannelId::Radiance, "radiance");
  g.add_output(config);
  return g;
}

TEST(GraphSpec, UnknownShaderBindingOrConstantNameIsRejected) {
  pipelines::GraphSpec g = passthrough_graph();
  EXPECT_THROW(g.add_pass("p", "no_such_shader"), std::logic_error);
  auto& pass = g.add_pass("p", "passthrough");
  EXPECT_THROW(pass.bind("radiance_plane", "radiance"), std::logic_error);
  EXPECT_THROW(pass.set("RADIANCE_IS_HALF", 1), std::logic_error);
  pass.bind("radiance", "radiance");
  EXPECT_THROW(pass.bind("radiance", "radiance"), std::logic_error);  // twice
  auto& taa = g.add_pass("t", "svgf_taa");
  EXPECT_THROW(taa.set("DISPLAY_LAGS", 1), std::logic_error);
  EXPECT_THROW(taa.set("DISPLAY_LAG", 2), std::logic_error);          // bool
  taa.set("DISPLAY_LAG", 1);
  EXPECT_THROW(taa.set("DISPLAY_LAG", 0), std::logic_error);          // twice
}

// Grid arguments by name: each lands in the push-constant word its row in
// the .pass file numbers (pyramid_probe: level, factor, width0, height0), of
// its declared type; an unknown name, the other type or no grid is refused.
TEST(GraphSpec, GridArgumentsAreSetByNameInTheirDeclaredSlot) {
  pipelines::GraphSpec g = passthrough_graph();
  auto& pass = g.add_pass("fill", "pyramid_probe");
  EXPECT_THROW(pass.arg("level", 1u), std::logic_error);  // before over_grid
  pass.over_grid({9, 3}, {9, 3});
  pass.arg("height0", 7u).arg("level", 2u).arg("width0", 5u);
  EXPECT_EQ(pass.grid->push.args[0], 2u);
  EXPECT_EQ(pass.grid->push.args[1], 0u);  // factor: unset
  EXPECT_EQ(pass.grid->push.args[2], 5u);
  EXPECT_EQ(pass.grid->push.args[3], 7u);
  EXPECT_THROW(pass.arg("levels", 1u), std::logic_error);  // no such argument
  EXPECT_THROW(pass.arg("factor", 3.0f), std::logic_error);  // a uint
  auto& tile = g.add_pass("tile", "tile_probe");
  tile.over_grid({9, 3}, {9, 3}).arg("sigma", 1.5f);
  EXPECT_EQ(tile.grid->push.args[1], std::bit_cast<uint32_t>(1.5f));
  EXPECT_THROW(tile.arg("sigma", 1u), std::logic_error);  // a float
}

// Modes by name (svgf_clip_prefilter: current, horizontal, vertical): mode()
// sets MODE to the mode's value and makes its needs required; MODE itself
// cannot be set, and a pass of a shader with modes must select one.
TEST(GraphSpec, ModesAreSelectedByNameAndRequireTheirBindings) {
  pipelines::GraphSpec g = passthrough_graph();
  for (const char* name : {"current", "partial", "depth_plane"}) g.add_scratch(name, 16);
  auto& current = g.add_pass("current", "svgf_clip_prefilter");
  current.bind("dst", "current").set("DEMODULATE", false);
  EXPECT_THROW(current.set("MODE", 0u), std::logic_error);
  EXPECT_THROW(current.mode("diagonal"), std::logic_error);
  EXPECT_THROW(g.check(), std::logic_error);  // no mode selected
  current.mode("current");
  EXPECT_EQ(current.unbound_required(), (std::vector<std::string_view>{"signal", "depth"}));
  EXPECT_THROW(g.check(), std::logic_error);
  current.bind("signal", "radiance").bind("depth", "depth_plane");
  auto& horizontal = g.add_pass("horizontal", "svgf_clip_prefilter");
  horizontal.bind("dst", "partial").mode("horizontal");
  EXPECT_EQ(horizontal.unbound_required(), (std::vector<std::string_view>{"src"}));  // no plane: only src
  horizontal.bind("src", "current");
  EXPECT_NO_THROW(g.check());
  const uint32_t mode_id = horizontal.declaration().constant("MODE")->id;
  const auto constants = horizontal.specialization(8);
  const auto mode = std::find_if(constants.begin(), constants.end(), [&](const auto& c) { return c.id == mode_id; });
  ASSERT_NE(mode, constants.end());
  EXPECT_EQ(mode->value, 1u);  // the second mode
}

// An alias reaches its buffer and costs no memory; from the first pass that
// binds it, no pass binds the buffer by its own name (its contents are dead).
TEST(GraphSpec, AnAliasReachesItsBufferAndEndsItsOldContents) {
  pipelines::GraphSpec g = passthrough_graph();
  g.add_scratch("frame", 12);
  const uint64_t bytes = g.device_bytes();
  g.add_alias("second_frame", "frame");
  EXPECT_EQ(g.device_bytes(), bytes);
  EXPECT_EQ(g.find("second_frame"), g.find("frame"));
  g.add_pass("first", "passthrough").bind("radiance", "radiance").bind("result", "frame");
  g.add_pass("second", "passthrough").bind("radiance", "radiance").bind("result", "second_frame");
  EXPECT_NO_THROW(g.check());
  g.add_pass("third", "passthrough").bind("radiance", "radiance").bind("result", "frame");
  EXPECT_THROW(g.check(), std::logic_error);
}

TEST(GraphSpec, AnAliasOfNoBufferOrWithABuffersNameIsRefused) {
  pipelines::GraphSpec g = passthrough_graph();
  g.add_alias("nothing_alias", "nothing");
  EXPECT_THROW(g.check(), std::logic_error);
  pipelines::GraphSpec h = passthrough_graph();
  h.add_scratch("frame", 12);
  h.add_alias("output", "frame");  // the Output buffer's name
  EXPECT_THROW(h.check(), std::logic_error);
}

TEST(GraphSpec, CheckRequiresEveryRequiredBindingAndDefinedBuffers) {
  pipelines::GraphSpec g = passthrough_graph();
  g.add_pass("p", "passthrough").bind("radiance", "radiance");
  try {
    g.check();
    FAIL() << "accepted a pass with an unbound required binding";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("result"), std::string::npos) << e.what();
  }
  pipelines::GraphSpec h = passthrough_graph();
  h.add_pass("p", "passthrough").bind("radiance", "radiance").bind("result", "no_such_buffer");
  EXPECT_THROW(h.check(), std::logic_error);
  pipelines::GraphSpec w = passthrough_graph();
  w.add_pass("p", "passthrough").bind("radiance", "output").bind("result", "radiance");  // writes an input
  EXPECT_THROW(w.check(), std::logic_error);
  pipelines::GraphSpec ok = passthrough_graph();
  ok.add_pass("p", "passthrough").bind("radiance", "radiance").bind("result", "output");
  EXPECT_NO_THROW(ok.check());
}

TEST(GraphSpec, OptionalBindingsMayStayUnbound) {
  pipelines::GraphSpec g = passthrough_graph();
  g.add_scratch("illum", 16);
  g.add_scratch("guide", 16);
  g.add_scratch("out", 16);
  g.add_scratch("temporal", 16);
  auto& pass = g.add_pass("a", "svgf_atrous");
  // colour_history and bandwidth: optional
  pass.bind("guide", "guide").bind("src", "illum").bind("dst", "out").bind("temporal", "temporal");
  EXPECT_NO_THROW(g.check());
  EXPECT_FALSE(g.passes[0].bindings()[3].bound());
  EXPECT_FALSE(g.passes[0].bindings()[5].bound());
}

// Every declared constant appears, by id, set or default: equal
// specializations give equal kernel-cache keys whatever order a builder sets them in.
TEST(GraphSpec, SpecializationListsEveryConstantById) {
  pipelines::PassSpec a("a", "svgf_atrous"), b("b", "svgf_atrous");
  a.set("BLOCK", 4).set("STEP", 2);
  b.set("STEP", 2);
  const auto sa = a.specialization(64), sb = b.specialization(64);
  EXPECT_EQ(sa, sb);  // BLOCK's default is 4
  ASSERT_EQ(sa.size(), 15u);
  EXPECT_EQ(sa[0], (gpu::SpecConstant{0, 64}));
  EXPECT_EQ(sa[1], (gpu::SpecConstant{1, 2}));
  EXPECT_EQ(sa[2], (gpu::SpecConstant{2, 0}));
  EXPECT_EQ(sa[3], (gpu::SpecConstant{3, 4}));
  EXPECT_EQ(sa[4], (gpu::SpecConstant{4, 0}));  // CLASS_EDGES' default
  EXPECT_EQ(sa[5], (gpu::SpecConstant{5, 0}));  // SPATIAL_BANDWIDTH's default
  EXPECT_EQ(sa[6], (gpu::SpecConstant{6, 2}));  // KERNEL_RADIUS's default: svgf's 5x5
  for (uint32_t id = 7; id <= 10; ++id) EXPECT_EQ(sa[id], (gpu::SpecConstant{id, 0}));  // progressive's switches off
  EXPECT_EQ(sa[11], (gpu::SpecConstant{11, 1}));  // SIGNALS' default: one signal
  EXPECT_EQ(sa[12], (gpu::SpecConstant{12, 0}));  // SECOND_GUIDE's default
  EXPECT_EQ(sa[13], (gpu::SpecConstant{13, 0xffffffffu}));  // NORMAL_POWER's default: -1, exp2(phi log2 cos)
  EXPECT_EQ(sa[14], (gpu::SpecConstant{14, 0}));  // LUMINANCE_RAMP's default
}

// A buffer added without a size takes it from the DN_PER_PIXEL rules of the
// bindings that bind it (through an alias too): reflect_prepare's modulator
// holds 3 floats per pixel, svgf_reproject's illum one vec4; rules that
// disagree, or none at all, are refused with the names involved.
TEST(GraphSpec, BuffersAreSizedByTheirBindingsRules) {
  pipelines::GraphSpec g = passthrough_graph();  // 4 x 2 pixels
  g.add_scratch("modulator");
  g.add_scratch("illum");
  g.add_alias("illum_again", "illum");
  g.add_pass("prepare", "reflect_prepare").bind("modulator", "modulator");
  g.add_pass("reproject", "svgf_reproject").bind("illum", "illum");
  g.add_pass("variance", "svgf_variance").bind("illum", "illum_again");
  EXPECT_THROW(g.check(), std::logic_error);  // not sized yet
  g.size_from_bindings();
  EXPECT_EQ(g.find("modulator")->bytes, 4u * 2 * 3 * 4);
  EXPECT_EQ(g.find("illum")->bytes, 4u * 2 * 16);

  pipelines::GraphSpec disagree = passthrough_graph();
  disagree.add_scratch("both");
  disagree.add_pass("prepare", "reflect_prepare").bind("modulator", "both");
  disagree.add_pass("reproject", "svgf_reproject").bind("illum", "both");
  try {
    disagree.size_from_bindings();
    ADD_FAILURE() << "disagreeing rules accepted";
  } catch (const std::logic_error& e) {
    EXPECT_EQ(std::string(e.what()), "buffer both: reproject.illum declares 128 bytes, prepare.modulator 96");
  }

  pipelines::GraphSpec unsized = passthrough_graph();
  unsized.add_scratch("read_only");
  unsized.add_pass("atrous", "svgf_atrous").bind("src", "read_only");  // a texel read declares no size
  try {
    unsized.size_from_bindings();
    ADD_FAILURE() << "a buffer without a rule accepted";
  } catch (const std::logic_error& e) {
    EXPECT_EQ(std::string(e.what()), "buffer read_only has no size: no binding of it declares DN_PER_PIXEL");
  }
}

// Every pipeline, in every input form it accepts (input_forms.hpp), builds a
// graph whose buffers its bindings size and that passes check().
TEST(GraphSpec, EveryPipelineBuildsACheckedGraphInEveryInputForm) {
  for (const auto& def : pipelines::definitions()) {
    SCOPED_TRACE(def.description.name);
    const auto forms = pipelines::input_forms(def.description);
    EXPECT_FALSE(forms.empty());
    for (uint64_t form : forms) {
      SCOPED_TRACE(form);
      const auto config = pipelines::form_config(def.description, form, 33, 17);
      ASSERT_FALSE(pipelines::validate(config).has_value()) << pipelines::validate(config)->message;
      EXPECT_NO_THROW({
        pipelines::GraphSpec g = def.build(config);
        g.size_from_bindings();
        g.check();
      });
    }
  }
}

}  // namespace
}  // namespace dn
