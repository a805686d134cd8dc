// svgf: spatiotemporal variance-guided filtering (Schied et al. 2017) with
// Falcor's defaults (shaders/svgf_*.comp, docs/pipelines.md "svgf in detail").
// Passes: svgf_reproject, svgf_variance, svgf_atrous_<i> for i < atrous_iterations
// (step 2^i as specialization constant 3: one pipeline per iteration),
// svgf_remodulate. Split mode (Diffuse + Specular declared instead of
// Radiance): one reproject/variance/a-trous chain per signal (pass names
// suffixed _diffuse / _specular), specular not demodulated (spec constant 6
// of svgf_reproject), the guide written by the diffuse chain only (7).
#include <algorithm>
#include <optional>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/fb_lut.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Per pixel, a single persistent copy (svgf_reproject reads it; svgf_variance
// and the feedback a-trous iteration rewrite it after that pass):
// vec4(demodulated rgb, length) fp32 and uvec4(m1, m2, depth as fp32 bits,
// octahedral snorm16x2 normal).
constexpr uint64_t kColourHistoryBytes = 16;
constexpr uint64_t kAuxHistoryBytes = 16;
// TAA (taa_alpha > 0): the previous final output, rgb fp32, one persistent
// copy (read by svgf_remodulate, rewritten by svgf_taa after it).
constexpr uint64_t kTaaHistoryBytes = 12;
// Scratch, per pixel: vec4(demodulated rgb, variance) fp32, two for the a-trous ping-pong.
constexpr uint64_t kIlluminationBytes = 16;
// Scratch, per pixel: guide uvec4(signed depth, packed normal, dz, 0) and
// temporal vec4(m1, m2, length, luminance), written by svgf_reproject.
constexpr uint64_t kGuideBytes = 16;
constexpr uint64_t kTemporalBytes = 16;
// svgf-fb scratch, per pixel: F_beta rgb fp32 (svgf_fb_factor).
constexpr uint64_t kFbFactorBytes = 12;
// a-trous register block: one invocation filters kAtrousBlock^2 pixels.
constexpr uint32_t kAtrousBlock = 4;
// svgf_variance register block: kVarianceBlock^2 pixels per invocation.
constexpr uint32_t kVarianceBlock = 2;

bool has_channel(const SessionConfig& config, ChannelId id) {
  for (const auto& c : config.channels)
    if (c.id == id) return true;
  return false;
}

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  const bool emission = has_channel(config, ChannelId::Emission);
  // Split mode (validate() guarantees Diffuse and Specular together, without Radiance).
  const bool split = has_channel(config, ChannelId::Diffuse);
  // svgf-fb: split mode with the specular signal demodulated by F_beta (always split).
  const bool fb = config.pipeline == "svgf-fb";
  if (split) {
    g.add_input(config, ChannelId::Diffuse, "diffuse");
    g.add_input(config, ChannelId::Specular, "specular");
  } else {
    g.add_input(config, ChannelId::Radiance, "radiance");
  }
  g.add_input(config, ChannelId::Albedo, "albedo");
  g.add_input(config, ChannelId::Normal, "normal");
  g.add_input(config, ChannelId::Depth, "depth");
  g.add_input(config, ChannelId::Motion, "motion");
  if (emission) g.add_input(config, ChannelId::Emission, "emission");
  if (fb) {
    g.add_input(config, ChannelId::SpecularF0, "specular_f0");
    g.add_input(config, ChannelId::Roughness, "roughness");
    g.add_shared("fb_lut", fb_lut_buffer);
  }
  g.add_persistent("svgf_colour", kColourHistoryBytes);
  g.add_persistent("svgf_aux", kAuxHistoryBytes);
  if (split) {
    g.add_persistent("svgf_spec_colour", kColourHistoryBytes);
    g.add_persistent("svgf_spec_aux", kAuxHistoryBytes);
  }
  const bool taa = g.parameters.svgf_taa_alpha > 0.0f;
  if (taa) g.add_persistent("svgf_taa", kTaaHistoryBytes);
  const uint32_t iterations = static_cast<uint32_t>(g.parameters.svgf_atrous_iterations);
  const uint32_t tap = std::min(static_cast<uint32_t>(g.parameters.svgf_feedback_tap), iterations ? iterations - 1 : 0u);
  // Split mode: the specular chain ping-pongs between svgf_illum_c and the
  // diffuse chain's non-final illumination buffer (the diffuse result stays
  // for svgf_remodulate); guide and temporal are shared (the diffuse chain
  // is done with temporal before the specular reprojection rewrites it).
  g.add_scratch("svgf_illum_a", kIlluminationBytes);
  if (iterations > 0) g.add_scratch("svgf_illum_b", kIlluminationBytes);
  if (split) g.add_scratch("svgf_illum_c", kIlluminationBytes);
  g.add_scratch("svgf_guide", kGuideBytes);
  g.add_scratch("svgf_temporal", kTemporalBytes);
  if (fb) g.add_scratch("svgf_fb", kFbFactorBytes);
  g.add_output(config);

  const uint32_t albedo_half = is_half(channel_format(config, ChannelId::Albedo));
  const uint32_t normal_half = is_half(channel_format(config, ChannelId::Normal));
  const uint32_t depth_half = is_half(channel_format(config, ChannelId::Depth));
  const uint32_t motion_half = is_half(channel_format(config, ChannelId::Motion));

  // One reproject / variance / a-trous chain over `signal`; returns the
  // buffer holding its final illumination. The first chain writes the guide
  // (spec constant 7), the others only read what it wrote.
  // demodulator: the plane the signal is divided by ("albedo", or svgf-fb's
  // "svgf_fb"), "" for none.
  auto chain = [&](ChannelId channel, const std::string& signal, const std::string& colour, const std::string& aux,
                   std::string current, std::string other, const std::string& demodulator, bool write_guide,
                   const std::string& suffix) {
    const bool demodulate = !demodulator.empty();
    const uint32_t demodulator_half = demodulator == "albedo" ? albedo_half : 0u;
    // Radiance includes emission; diffuse and specular do not (docs/protocol.md).
    const bool subtract_emission = emission && channel == ChannelId::Radiance;
    PassSpec& reproject = g.add_pass("svgf_reproject" + suffix, "svgf_reproject");
    reproject.bind("signal", signal)
        .bind("normal", "normal")
        .bind("depth", "depth")
        .bind("motion", "motion")
        .bind("prev_colour", colour)
        .bind("prev_aux", aux)
        .bind("illum", current)
        .bind("guide", "svgf_guide")
        .bind("temporal", "svgf_temporal")
        .set("SIGNAL_HALF", is_half(channel_format(config, channel)))
        .set("MODULATOR_HALF", demodulator_half)
        .set("NORMAL_HALF", normal_half)
        .set("DEPTH_HALF", depth_half)
        .set("MOTION_HALF", motion_half)
        .set("DEMODULATE", demodulate)
        .set("WRITE_GUIDE", write_guide)
        .set("SUBTRACT_EMISSION", subtract_emission);
    if (demodulate) reproject.bind("modulator", demodulator);
    if (subtract_emission)
      reproject.bind("emission", "emission").set("EMISSION_HALF", is_half(channel_format(config, ChannelId::Emission)));
    reproject.pixels_per_invocation = 1;

    PassSpec& variance = g.add_pass("svgf_variance" + suffix, "svgf_variance");
    variance.bind("guide", "svgf_guide")
        .bind("temporal", "svgf_temporal")
        .bind("illum", current)
        .bind("colour_history", colour)
        .bind("aux_history", aux)
        .set("BLOCK", kVarianceBlock);
    variance.invocations = uint64_t{(config.width + kVarianceBlock - 1) / kVarianceBlock} *
                           ((config.height + kVarianceBlock - 1) / kVarianceBlock);

    for (uint32_t i = 0; i < iterations; ++i) {
      PassSpec& atrous = g.add_pass("svgf_atrous_" + std::to_string(i) + suffix, "svgf_atrous");
      atrous.bind("guide", "svgf_guide")
          .bind("src", current)
          .bind("dst", other)
          .set("STEP", 1u << i)
          .set("FEEDBACK", i == tap)
          .set("BLOCK", kAtrousBlock);
      if (i == tap) atrous.bind("colour_history", colour);
      // Grid of shaders/svgf_atrous.comp: (ceil(W / span) * step) x (ceil(H / span) * step), span = step * block.
      const uint64_t step = uint64_t{1} << i, span = step * kAtrousBlock;
      atrous.invocations = ((config.width + span - 1) / span * step) * ((config.height + span - 1) / span * step);
      std::swap(current, other);
    }
    return current;
  };

  if (fb) {
    PassSpec& factor = g.add_pass("svgf_fb_factor", "svgf_fb_factor");
    factor.bind("specular_f0", "specular_f0")
        .bind("roughness", "roughness")
        .bind("normal", "normal")
        .bind("depth", "depth")
        .bind("fb_lut", "fb_lut")
        .bind("factor", "svgf_fb")
        .set("F0_HALF", is_half(channel_format(config, ChannelId::SpecularF0)))
        .set("ROUGHNESS_HALF", is_half(channel_format(config, ChannelId::Roughness)))
        .set("NORMAL_HALF", normal_half)
        .set("DEPTH_HALF", depth_half);
    factor.pixels_per_invocation = 1;
  }

  std::string diffuse_result, specular_result;
  if (split) {
    diffuse_result = chain(ChannelId::Diffuse, "diffuse", "svgf_colour", "svgf_aux", "svgf_illum_a", "svgf_illum_b",
                           "albedo", true, "_diffuse");
    const std::string spare = diffuse_result == "svgf_illum_a" ? "svgf_illum_b" : "svgf_illum_a";
    // svgf-fb divides by F_beta unless the client sent L_W already.
    const bool divide_by_fb = fb && g.parameters.svgf_fb_specular_demodulated == 0.0f;
    specular_result = chain(ChannelId::Specular, "specular", "svgf_spec_colour", "svgf_spec_aux", "svgf_illum_c",
                            spare, divide_by_fb ? "svgf_fb" : "", false, "_specular");
  } else {
    diffuse_result = chain(ChannelId::Radiance, "radiance", "svgf_colour", "svgf_aux", "svgf_illum_a",
                           "svgf_illum_b", "albedo", true, "");
  }

  // With TAA, svgf_remodulate writes the current colour to svgf_temporal and
  // the reprojected TAA history to svgf_guide (both free once the a-trous
  // chains are done) instead of Output; svgf_taa blends them. Without it,
  // the TAA bindings stay unbound.
  PassSpec& remodulate = g.add_pass("svgf_remodulate", "svgf_remodulate");
  remodulate.bind("illum", diffuse_result)
      .bind("albedo", "albedo")
      .bind("result", "output")
      .set("ALBEDO_HALF", albedo_half)
      .set("HAS_EMISSION", emission)
      .set("OUTPUT_HALF", is_half(config.output_format))
      .set("HAS_SPECULAR", split)
      .set("SPECULAR_FACTOR", fb)
      .set("TAA", taa);
  if (emission) remodulate.bind("emission", "emission").set("EMISSION_HALF", is_half(channel_format(config, ChannelId::Emission)));
  if (split) remodulate.bind("specular", specular_result);
  if (fb) remodulate.bind("specular_factor", "svgf_fb");
  if (taa)
    remodulate.bind("depth", "depth")
        .bind("motion", "motion")
        .bind("taa_history", "svgf_taa")
        .bind("taa_current", "svgf_temporal")
        .bind("taa_previous", "svgf_guide")
        .set("DEPTH_HALF", depth_half)
        .set("MOTION_HALF", motion_half);

  if (taa)
    g.add_pass("svgf_taa", "svgf_taa")
        .bind("current", "svgf_temporal")
        .bind("previous", "svgf_guide")
        .bind("result", "output")
        .bind("history", "svgf_taa")
        .set("OUTPUT_HALF", is_half(config.output_format));
  return g;
}

// The either/or rule of the lighting channels (validate() has checked each
// channel on its own and the required ones).
std::optional<ConfigError> check_channels(const SessionConfig& config) {
  using protocol::ErrorCode;
  int radiance = -1, diffuse = -1, specular = -1;
  for (size_t i = 0; i < config.channels.size(); ++i) {
    if (config.channels[i].id == ChannelId::Radiance) radiance = static_cast<int>(i);
    if (config.channels[i].id == ChannelId::Diffuse) diffuse = static_cast<int>(i);
    if (config.channels[i].id == ChannelId::Specular) specular = static_cast<int>(i);
  }
  if (radiance >= 0 && (diffuse >= 0 || specular >= 0)) {
    const int other = diffuse >= 0 ? diffuse : specular;
    return ConfigError{ErrorCode::InvalidChannel,
                       "OPEN_SESSION.channels[" + std::to_string(std::max(radiance, other)) + "].id",
                       "pipeline svgf takes either radiance or diffuse + specular, not both (radiance and " +
                           std::string(diffuse >= 0 ? "diffuse" : "specular") + " declared)"};
  }
  if (diffuse >= 0 && specular < 0)
    return ConfigError{ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                       "pipeline svgf requires channel specular together with diffuse"};
  if (specular >= 0 && diffuse < 0)
    return ConfigError{ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                       "pipeline svgf requires channel diffuse together with specular"};
  if (radiance < 0 && diffuse < 0)
    return ConfigError{ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                       "pipeline svgf requires channel radiance, or diffuse and specular"};
  return std::nullopt;
}

}  // namespace

PipelineDefinition svgf_definition() {
  PipelineDefinition d;
  d.description.name = "svgf";
  d.description.summary =
      "Spatiotemporal variance-guided filtering (Schied 2017, Falcor defaults): albedo demodulation, temporal "
      "integration of colour and luminance moments, variance-guided a-trous wavelet filter; Emission is added back "
      "unfiltered.";
  // Radiance, or Diffuse + Specular (check_channels): both forms are optional in the masks.
  d.description.required_channels = protocol::channel_bit(ChannelId::Albedo) |
                                     protocol::channel_bit(ChannelId::Normal) |
                                     protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Radiance) |
                                     protocol::channel_bit(ChannelId::Diffuse) |
                                     protocol::channel_bit(ChannelId::Specular) |
                                     protocol::channel_bit(ChannelId::Emission);
  d.parameter_groups = {"svgf"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  d.check_channels = check_channels;
  return d;
}

PipelineDefinition svgf_fb_definition() {
  PipelineDefinition d;
  d.description.name = "svgf-fb";
  d.description.summary =
      "svgf on split lighting with BRDF pre-integration demodulation (paper 000): diffuse divided by albedo, "
      "specular by F_beta = F0 * A + B from a GGX table computed on the device at start-up; both filtered as "
      "svgf and remodulated. Parameter specular_demodulated = 1 takes L_W (Eq. 11) in the specular channel.";
  d.description.required_channels =
      protocol::channel_bit(ChannelId::Diffuse) | protocol::channel_bit(ChannelId::Specular) |
      protocol::channel_bit(ChannelId::Albedo) | protocol::channel_bit(ChannelId::SpecularF0) |
      protocol::channel_bit(ChannelId::Roughness) | protocol::channel_bit(ChannelId::Normal) |
      protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Emission);
  d.parameter_groups = {"svgf", "svgf_fb"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  return d;
}

}  // namespace dn::pipelines
