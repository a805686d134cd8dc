// reflect: temporally stable reflections (paper 001, Voorhuis 2018, "Beyond
// SVGF"; docs/pipelines.md "reflect") as a variant of svgf-fb: the diffuse
// signal is svgf-fb's (albedo, primary motion), while the specular signal
//  - is reprojected with reflection motion (reflect_motion: a diamond search
//    over the first non-mirror hit at mirrors, Eq. 1, and over
//    representative rays at glossy pixels, Eq. 4-5), so one pixel's diffuse
//    and specular parts move each with its own motion;
//  - is demodulated by F_beta times the reflected albedo at mirrors, so
//    neither the mirror's Fresnel nor the reflected texture is blurred;
//  - edge-stops and tests its history on the reflected surface's normal and
//    virtual depth at mirrors, with the depth and normal tests off at glossy
//    pixels (clipping guards those);
//  - finds that motion from three starts with virtual_start: the pixel, its
//    primary motion and the virtual point's motion (NRD's);
//  - with footprint_omega > 0 and a reflection_footprint plane, is filtered
//    with Eq. 6's ray-differential spatial bandwidth at glossy pixels;
// with the reflection features of docs/protocol.md §7.5 as inputs. Passes in
// front of the SVGF chains: svgf_fb_factor, reflect_prepare, reflect_motion.
#include "pipelines/definitions.hpp"

#include "pipelines/stages/fb_factor.hpp"
#include "pipelines/stages/split_signals.hpp"
#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Scratch, per pixel, fp32: F_beta (svgf_fb_factor, fb_factor.hpp); the specular
// modulator rgb, its depth and normal (reflect_prepare); the specular motion
// vec4 (reflect_motion).
constexpr const char* kFactor = "svgf_fb";
constexpr const char* kModulator = "reflect_modulator";
constexpr const char* kFeatureDepth = "reflect_depth";
constexpr const char* kFeatureNormal = "reflect_normal";
constexpr const char* kMotion = "reflect_motion";
// Eq. 6's sigma per pixel, fp32 (reflect_prepare), when the session sends
// reflection_footprint and footprint_omega > 0.
constexpr const char* kBandwidth = "reflect_bandwidth";
// The virtual point's motion per pixel, vec2 fp32 (reflect_prepare), the
// search's third start, with virtual_start.
constexpr const char* kVirtualMotion = "reflect_virtual_motion";
// History (this frame's and the previous frame's copy): the search features,
// two vec4 per pixel (shaders/include/reflect.glsl).
constexpr const char* kFeatures = "reflect_features";
// The displayed frame before the firefly median (SvgfVariant::display).
constexpr const char* kDisplay = "reflect_display";

// The reflection feature planes reflect_prepare reads: channel, binding and buffer name.
constexpr ChannelId kFeatureChannels[] = {ChannelId::Position,           ChannelId::ReflectionPosition,
                                          ChannelId::ReflectionAlbedo,   ChannelId::ReflectionNormal,
                                          ChannelId::ReflectionDepth,    ChannelId::ReflectionDirection,
                                          ChannelId::ReflectionDistance};

bool takes_footprint(const SessionConfig& config, const Parameters& p) {
  return p.reflect_footprint_omega > 0.0f && has_channel(config, ChannelId::ReflectionFootprint);
}

SvgfVariant variant(const SessionConfig& config, const Parameters& p) {
  SvgfVariant v = svgf_variant_from(config, p);
  v.signals = split_signals(config, Modulator{kModulator, std::nullopt});
  SvgfSignal& specular = v.signals[1];
  specular.motion = MotionSource::Reflection;
  specular.reflection_motion = kMotion;
  specular.features = SignalFeatures{kFeatureDepth, kFeatureNormal};
  specular.reads_history = p.reflect_specular_history != 0.0f;
  specular.specular_alpha = true;
  if (p.reflect_firefly_median != 0.0f) v.display = kDisplay;
  if (takes_footprint(config, p)) specular.spatial_bandwidth = kBandwidth;
  return v;
}

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  const SvgfVariant v = variant(config, g.parameters);
  add_svgf_inputs(g, config, v);
  for (ChannelId id : kFeatureChannels) g.add_input(config, id, std::string(protocol::find_channel(id)->name));
  const bool footprint = takes_footprint(config, g.parameters);
  if (footprint) g.add_input(config, ChannelId::ReflectionFootprint, "reflection_footprint");
  add_svgf_buffers(g, v);
  g.add_scratch(kModulator);
  g.add_scratch(kFeatureDepth);
  g.add_scratch(kFeatureNormal);
  g.add_scratch(kMotion);
  if (footprint) g.add_scratch(kBandwidth);
  const bool virtual_start = g.parameters.reflect_virtual_start != 0.0f;
  if (virtual_start) g.add_scratch(kVirtualMotion);
  g.add_history(kFeatures);
  g.add_output(config);

  add_fb_factor(g, config, kFactor);

  PassSpec& prepare = g.add_pass("reflect_prepare", "reflect_prepare");
  prepare.bind("roughness", "roughness")
      .bind("depth", "depth")
      .bind("normal", "normal")
      .bind("fb_factor", kFactor)
      .bind("features", kFeatures)
      .bind("modulator", kModulator)
      .bind("feature_depth", kFeatureDepth)
      .bind("feature_normal", kFeatureNormal);
  for (ChannelId id : kFeatureChannels) {
    const std::string name(protocol::find_channel(id)->name);
    prepare.bind(name, name);
  }
  if (footprint)
    prepare.bind("reflection_footprint", "reflection_footprint")
        .bind("bandwidth", kBandwidth)
        .set("FOOTPRINT", 1u);
  if (virtual_start) prepare.bind("virtual_motion", kVirtualMotion).set("VIRTUAL_START", 1u);
  prepare.pixels_per_invocation = 1;

  PassSpec& search = g.add_pass("reflect_motion", "reflect_motion");
  search.bind("features", kFeatures)
      .bind("prev_features", kFeatures, Slot::Previous)
      .bind("motion", "motion")
      .bind("result", kMotion);
  if (virtual_start) search.bind("virtual_motion", kVirtualMotion).set("VIRTUAL_START", 1u);
  search.pixels_per_invocation = 1;

  add_svgf_passes(g, config, v);
  if (!v.display.empty()) {
    PassSpec& median = g.add_pass("reflect_median", "reflect_median");
    median.bind("src", kDisplay)
        .bind("features", kFeatures)
        .bind("depth", "depth")
        .bind("result", v.extra_samples ? kSupersampleDisplay : GraphSpec::kOutput);
    if (v.emission)
      median.bind("emission", "emission")
          .set("HAS_EMISSION", 1u);
    if (const std::string still = still_mean_buffer(v); !still.empty())
      median.bind("still_mean", still).bind("still_m2", still_m2_buffer(v)).set("CONVERGE_STILL", 1u);
    if (v.extra_samples) add_supersample_resolve(g, config, kSupersampleDisplay);
  }
  return g;
}

}  // namespace

PipelineDefinition reflect_definition() {
  PipelineDefinition d;
  d.description.name = "reflect";
  d.description.summary =
      "svgf-fb with temporally stable reflections (paper 001, Beyond SVGF): the specular signal is reprojected "
      "with reflection motion found by diamond search over the reflection features (mirror: first non-mirror hit, "
      "glossy: representative ray), demodulated by F_beta times the reflected albedo and edge-stopped on the "
      "reflected surface at mirrors; the diffuse signal keeps the primary motion.";
  uint64_t required = 0;
  for (ChannelId id : {ChannelId::Specular, ChannelId::Albedo, ChannelId::SpecularF0, ChannelId::Roughness,
                       ChannelId::Normal, ChannelId::Depth, ChannelId::Motion})
    required |= protocol::channel_bit(id);
  for (ChannelId id : kFeatureChannels) required |= protocol::channel_bit(id);
  d.description.required_channels = required;
  d.description.optional_channels = protocol::channel_bit(ChannelId::Diffuse) |
                                     protocol::channel_bit(ChannelId::DiffuseLighting) |
                                     protocol::channel_bit(ChannelId::Emission) |
                                     protocol::channel_bit(ChannelId::ReflectionFootprint) | extra_sample_channel_bits();
  d.parameter_groups = {"svgf", "specular", "reflect"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.shared_resources = {kFbLutResource};
  d.build = build;
  d.check_channels = check_split_only;
  return d;
}

}  // namespace dn::pipelines
