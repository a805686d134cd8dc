// What a session of each pipeline costs in device memory, as the affine model
// bytes = fixed + per_pixel * width * height a placer can evaluate for any size
// (STATS pipeline.<name>.device_bytes_fixed / _per_pixel, docs/server.md "Capacity").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/pipelines/pipeline.hpp"

namespace dn::server {

struct PipelineCost {
  std::string pipeline;
  double fixed_bytes = 0;      // what a session needs whatever its size
  double bytes_per_pixel = 0;  // and per pixel of width * height
  uint64_t reference_channels = 0;  // protocol::channel_bit mask of the reference session's channels
};

// The reference session of a pipeline: every channel it accepts (required and
// optional) in F32, F32 output, default parameters, less the channels that
// exclude others (each one a refusal names; svgf keeps radiance, not the
// diffuse + specular split). Fewer channels or F16 cost less.
pipelines::SessionConfig reference_session(const pipelines::PipelineDescription& pipeline, uint32_t width,
                                           uint32_t height);

// The model of one pipeline, fitted to prepare()'s estimate of its reference
// session at two sizes; an empty `pipeline` when prepare() refuses that session.
PipelineCost fit_pipeline_cost(const pipelines::PipelineDescription& pipeline);

// Every available pipeline's model, fitted once (the estimates are pure data).
const std::vector<PipelineCost>& pipeline_costs();

}  // namespace dn::server
