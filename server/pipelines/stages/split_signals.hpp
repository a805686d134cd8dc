// The split signals of a session and their forms (docs/protocol.md §7.4):
// diffuse is `diffuse` (radiance: the server divides by albedo) or
// `diffuse_lighting` (already divided by albedo: the server only multiplies);
// specular is `specular` (radiance: divided by specular_albedo when declared,
// else by the pipeline's own modulator) or `specular_lighting` (already
// divided by specular_albedo, which it requires). One rule for every pipeline
// that filters split signals, so no pipeline has its own switch for it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pipelines/definitions.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines {

// True when the session declared any split channel (either form).
bool has_split_signals(const SessionConfig& config);

// The diffuse and specular signals, in that order. `specular_default` is the
// modulator of a radiance-form `specular` without `specular_albedo` (empty:
// filtered as sent). Call after check_split_channels().
std::vector<SvgfSignal> split_signals(const SessionConfig& config, const Modulator& specular_default);

// svgf's signals, which its variants (progressive) share: the split pair
// (split_signals, specular filtered as sent without specular_albedo) when the
// session declared it, else radiance demodulated by albedo, its emission
// subtracted when `emission` (added back after filtering), its history clipped.
std::vector<SvgfSignal> radiance_or_split_signals(const SessionConfig& config, bool emission);

// The either/or rules: one form per signal, diffuse and specular together,
// specular_lighting with specular_albedo; `radiance_allowed`: the pipeline
// also takes `radiance` instead of the split pair (never both). Which forms
// a pipeline takes at all is its channel masks' business.
std::optional<ConfigError> check_split_channels(const SessionConfig& config, const std::string& pipeline,
                                                bool radiance_allowed);

// PipelineDefinition::check_channels of a pipeline that takes the split
// pair only (svgf-fb, reflect): check_split_channels without radiance,
// naming config.pipeline.
std::optional<ConfigError> check_split_only(const SessionConfig& config);

// Channel bits of both forms of both signals and of specular_albedo.
uint64_t split_channel_bits();

}  // namespace dn::pipelines
