// The tunables of every pipeline, from the one table in
// shaders/include/parameters.def (shared with the shaders, which read row
// <group>, <name> as DN_PARAM_VALUE(group, name) from the uniform block's
// parameter struct).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// The uniform block's parameter struct (shaders/include/frame.glsl
// DnParameters): one float per row of parameters.def, in row order. std140
// lays consecutive floats out as C++ does; alignas(16) gives the struct the
// size std140 rounds it to. The spirv.* tests compare the offsets.
struct alignas(16) Parameters {
#define DN_PARAM(group, name, def, lo, hi, isint, desc) float group##_##name = 0.0f;
#include "parameters.def"
#undef DN_PARAM
};

struct ParameterDef {
  std::string_view group;
  ParameterInfo info;
  float Parameters::*member = nullptr;  // where the value goes in the uniform block
};

// Every row of parameters.def, in file order.
const std::vector<ParameterDef>& parameter_table();

// A pipeline's parameter groups (PipelineDefinition::parameter_groups), in order.
using ParameterGroups = std::span<const std::string_view>;

// The parameters of these groups: group by group, each in table order.
// Throws std::logic_error for a group with no row, or a name two groups share.
std::vector<ParameterInfo> parameters_of(ParameterGroups groups);

// The uniform block's parameters for a session taking `groups`: defaults,
// overridden by `values` (which passed validate()); other groups' rows 0.
Parameters parameter_block(ParameterGroups groups, const std::vector<protocol::Parameter>& values);

// The values a session of `pipeline` runs with, in the order of its
// PipelineDescription::parameters (empty for an unknown pipeline).
std::vector<float> resolve_parameters(std::string_view pipeline, const std::vector<protocol::Parameter>& values);

}  // namespace dn::pipelines
