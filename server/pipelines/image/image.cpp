// image: one finished frame (colour, and whichever of albedo, normal and
// depth the renderer has), denoised from itself alone: no history, no
// motion, no camera (docs/pipelines.md, "image"). Its noise is estimated from
// the frame (image_prepare, image_gain, image_noise), filtered by a guided a-trous
// (image_atrous) and held near the input by the harm guard (image_output).
#include "pipelines/definitions.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Bins of the noise-gain histogram (image_gain.glsl), its passes' GAIN_BINS.
constexpr uint32_t kGainBins = 256;

// The guides a session declared, as each pass's HAS_* constants.
struct Guides {
  bool albedo = false, normal = false, depth = false;
  void set_on(PassSpec& pass, bool geometry = true) const {
    pass.set("HAS_ALBEDO", albedo);
    if (geometry) pass.set("HAS_NORMAL", normal).set("HAS_DEPTH", depth);
    if (albedo) pass.bind("albedo", "albedo");
    pass.pixels_per_invocation = 1;
  }
};

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  const Guides guides{has_channel(config, ChannelId::Albedo), has_channel(config, ChannelId::Normal),
                      has_channel(config, ChannelId::Depth)};
  g.add_input(config, ChannelId::Radiance, "radiance");
  if (guides.albedo) g.add_input(config, ChannelId::Albedo, "albedo");
  if (guides.normal) g.add_input(config, ChannelId::Normal, "normal");
  if (guides.depth) g.add_input(config, ChannelId::Depth, "depth");
  g.add_scratch("signal");
  g.add_scratch("guide");
  g.add_scratch("noisy");
  g.add_scratch_elements("noise_histogram", kGainBins + 1, sizeof(uint32_t));  // the bins, then the gain
  const uint32_t iterations = static_cast<uint32_t>(g.parameters.image_iterations);
  // The a-trous ping-pong; the first iteration reads noisy, which the output pass reads too.
  if (iterations > 0) g.add_scratch("filtered_a");
  if (iterations > 1) g.add_scratch("filtered_b");
  g.add_output(config);

  g.add_pass("image_gain_clear", "image_gain").mode("clear").bind("histogram", "noise_histogram")
      .set("GAIN_BINS", kGainBins).invocations = kGainBins + 1;
  PassSpec& prepare = g.add_pass("image_prepare", "image_prepare").bind("radiance", "radiance");
  if (guides.normal) prepare.bind("normal", "normal");
  if (guides.depth) prepare.bind("depth", "depth");
  prepare.bind("signal", "signal").bind("guide", "guide").bind("histogram", "noise_histogram");
  prepare.set("GAIN_BINS", kGainBins);
  guides.set_on(prepare);
  g.add_pass("image_gain", "image_gain").mode("median").bind("histogram", "noise_histogram")
      .set("GAIN_BINS", kGainBins).invocations = 1;

  PassSpec& noise = g.add_pass("image_noise", "image_noise").bind("signal", "signal").bind("guide", "guide");
  noise.bind("noisy", "noisy").bind("histogram", "noise_histogram").set("GAIN_BINS", kGainBins);
  guides.set_on(noise);

  std::string source = "noisy";
  for (uint32_t i = 0; i < iterations; ++i) {
    const std::string target = i % 2 == 0 ? "filtered_a" : "filtered_b";
    PassSpec& atrous = g.add_pass("image_atrous_" + std::to_string(i), "image_atrous");
    atrous.bind("src", source).bind("guide", "guide").bind("dst", target).set("STEP", 1u << i);
    guides.set_on(atrous);
    source = target;
  }

  PassSpec& output = g.add_pass("image_output", "image_output").bind("filtered", source).bind("noisy", "noisy");
  output.bind("result", GraphSpec::kOutput);
  guides.set_on(output, false);
  return g;
}

}  // namespace

PipelineDefinition image_definition() {
  PipelineDefinition d;
  d.description.name = "image";
  d.description.summary =
      "One finished frame denoised from itself: Radiance, with Albedo, Normal and Depth where the renderer has them "
      "(no motion, no history).";
  d.description.required_channels = protocol::channel_bit(ChannelId::Radiance);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Albedo) | protocol::channel_bit(ChannelId::Normal) |
                                    protocol::channel_bit(ChannelId::Depth);
  d.parameter_groups = {"image"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  return d;
}

}  // namespace dn::pipelines
