// Guide-ray supersampling (paper 001 §5; docs/pipelines.md "Extra samples"):
// a session that declares extra samples (protocol 1.4, ids 33-50) gets, in
// the SVGF chain, supersample_assign before the chains, one supersample_mix
// per signal (whose result the chain reads instead of the signal's plane)
// and supersample_resolve after the displayed frame.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// The extra samples a validated session declares (0 to 3).
uint32_t extra_samples(const SessionConfig& config);

// Bits of every extra-sample channel (the optional mask of the pipelines that take them).
uint64_t extra_sample_channel_bits();

// The rules beyond the masks: samples numbered 1, 2, ... without a gap; each
// with normal, depth, offset and the colour of every signal the session
// sends (radiance, or diffuse and specular; not with the lighting forms);
// one format per kind across the samples.
std::optional<ConfigError> check_extra_samples(const SessionConfig& config);

// Scratch: the assignment word (4 B per pixel) and, per signal plane in
// `inputs`, its mixed plane (fp32 rgb) named mixed_signal(input).
void add_supersample_buffers(GraphSpec& g, const std::vector<std::string>& inputs);
std::string mixed_signal(const std::string& input);
// The displayed frame before the resolve when no pass of the chain's caller
// provides one (rgb fp32 scratch).
inline constexpr const char* kSupersampleDisplay = "supersample_display";
// The extra samples' planes of the signal sent as `channel` (Radiance,
// Diffuse or Specular) and the features all signals share.
void add_supersample_inputs(GraphSpec& g, const SessionConfig& config, const std::vector<protocol::ChannelId>& signals);
void add_supersample_assign(GraphSpec& g, const SessionConfig& config);
void add_supersample_mix(GraphSpec& g, const SessionConfig& config, protocol::ChannelId signal, const std::string& input,
                         const std::string& suffix);
// Resolve: reads `display` (3 fp32 per pixel), writes Output.
void add_supersample_resolve(GraphSpec& g, const SessionConfig& config, const std::string& display);

}  // namespace dn::pipelines
