// Internal: the pipelines this build offers. Each definition describes
// itself (channels, parameters from parameters.def) and builds its pass graph
// from a validated SessionConfig.
#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "pipelines/graph.hpp"
#include "pipelines/parameters.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

struct PipelineDefinition {
  PipelineDescription description;
  // The parameters.def groups it takes, in order (description.parameters
  // lists their rows): svgf-fb takes svgf's group and its own.
  std::vector<std::string_view> parameter_groups;
  // Its own defaults for some of those rows (parameters.hpp ParameterDefaults;
  // description.parameters shows them): a variant of another pipeline's chain
  // keeps one definition per parameter and changes only its constants.
  ParameterDefaults parameter_defaults;
  GraphSpec (*build)(const SessionConfig& config);
  // Optional channel rules beyond the required/optional masks (run by
  // validate() after the per-channel checks); nullptr if none.
  std::optional<ConfigError> (*check_channels)(const SessionConfig& config) = nullptr;
  // Context-wide resources its graphs bind (GraphSpec::add_shared), so a
  // server can make them before the first session (prepare_shared_resources).
  std::vector<SharedResourceDecl> shared_resources;
};

// One per line of pipelines.def (each defined in its family folder).
#define DN_PIPELINE(family, id) PipelineDefinition id##_definition();
#include "pipelines/pipelines.def"
#undef DN_PIPELINE

// All definitions in a stable order; find_definition returns nullptr if unknown.
const std::vector<PipelineDefinition>& definitions();
const PipelineDefinition* find_definition(std::string_view name);

// Common start of every graph: resolution and resolved parameters.
GraphSpec begin_graph(const SessionConfig& config);

// The checks every pipeline shares: resolution, output format, each channel
// known, in f16 or f32, declared once and taken by `desc`, its required ones present.
std::optional<ConfigError> check_declaration(const SessionConfig& config, const PipelineDescription& desc);

// "radiance, albedo, normal": the channels of a protocol::channel_bit mask, in id order; "none" when empty.
std::string channel_list(uint64_t mask);

}  // namespace dn::pipelines
