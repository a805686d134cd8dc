// The tunables of every pipeline, from the one table the build makes of the
// pipeline folders' parameters.def rows (shaders/README.md, "Parameters";
// shared with the shaders, which read row <group>, <name> as
// DN_PARAM_VALUE(group, name) from the constants block's parameter struct).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// The constants block's parameter struct (shaders/include/frame.glsl
// DnParameters): one float per row of parameters.def, in row order. std140
// lays consecutive floats out as C++ does; alignas(16) gives the struct the
// size std140 rounds it to. The spirv.* tests compare the offsets.
struct alignas(16) Parameters {
#define DN_PARAM(group, name, def, lo, hi, isint, desc) float group##_##name = 0.0f;
#include "generated/parameters.def"
#undef DN_PARAM
};

struct ParameterDef {
  std::string_view group;
  ParameterInfo info;
  float Parameters::*member = nullptr;  // where the value goes in the constants block
};

// Every row of parameters.def, in file order.
const std::vector<ParameterDef>& parameter_table();

// A pipeline's parameter groups (PipelineDefinition::parameter_groups), in order.
using ParameterGroups = std::span<const std::string_view>;

// A pipeline's own defaults for rows of the groups it takes
// (PipelineDefinition::parameter_defaults): progressive runs svgf's rows with
// paper 004's constants. Each replaces the row's default for that pipeline only.
using ParameterDefaults = std::vector<ParameterValue>;

// The parameters of these groups: group by group, each in table order, with
// `defaults` applied. Throws std::logic_error for a group with no row, a name
// two groups share, or a default that names no row of the groups or lies
// outside its row's range (or is not integral where the row is).
std::vector<ParameterInfo> parameters_of(ParameterGroups groups, const ParameterDefaults& defaults = {});

// The constants block's parameters for a session taking `groups`: defaults
// (the pipeline's own where it has one), overridden by `values` (which passed
// validate()); other groups' rows 0.
Parameters parameter_block(ParameterGroups groups, const std::vector<ParameterValue>& values,
                           const ParameterDefaults& defaults = {});

// The values a session of `pipeline` runs with, in the order of its
// PipelineDescription::parameters (empty for an unknown pipeline).
std::vector<float> resolve_parameters(std::string_view pipeline, const std::vector<ParameterValue>& values);

}  // namespace dn::pipelines
