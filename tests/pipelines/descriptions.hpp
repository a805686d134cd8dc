// What a family's description test reads: a pipeline's description by name,
// its parameter names and defaults, and the channel masks the tests state.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::test {

inline const pipelines::PipelineDescription& description(const std::string& name) {
  for (const auto& d : pipelines::available_pipelines())
    if (d.name == name) return d;
  throw std::out_of_range("no pipeline " + name);
}

inline std::vector<std::string> parameter_names(const pipelines::PipelineDescription& d) {
  std::vector<std::string> names;
  for (const auto& p : d.parameters) names.push_back(p.name);
  return names;
}

// A parameter's default; -1 when the pipeline has no such parameter.
inline double default_of(const pipelines::PipelineDescription& d, const std::string& name) {
  for (const auto& p : d.parameters)
    if (p.name == name) return p.default_value;
  return -1.0;
}

inline uint64_t bits(std::initializer_list<protocol::ChannelId> ids) {
  uint64_t mask = 0;
  for (protocol::ChannelId id : ids) mask |= protocol::channel_bit(id);
  return mask;
}

// The extra samples, ids 33-50 (docs/protocol.md §7.6).
inline uint64_t extra_sample_bits() {
  uint64_t mask = 0;
  for (uint32_t id = 33; id <= 50; ++id) mask |= protocol::channel_bit(static_cast<protocol::ChannelId>(id));
  return mask;
}

// svgf's parameter rows, in order: the group svgf-fb, reflect and progressive take too.
inline const std::vector<std::string> kSvgfParameterNames = {
    "alpha_colour", "alpha_moments", "max_history", "atrous_iterations", "feedback_tap", "phi_colour",
    "phi_normal",   "phi_depth",     "taa_alpha",   "taa_static_alpha",  "clip_roughness", "variance_of_mean",
    "harm_guard",   "keep_unexplained", "converge_still", "luminance_ramp", "propagate_variance"};

}  // namespace dn::test
