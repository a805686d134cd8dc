// The tunables of every pipeline, from the one table in
// shaders/include/parameters.def (shared with the shaders, which read each
// value from FrameConstants.params[index]).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

inline constexpr uint32_t kMaxParameters = 16;  // FrameConstants.params

struct ParameterDef {
  std::string_view pipeline;
  uint32_t index = 0;  // slot in FrameConstants.params
  ParameterInfo info;
};

// Every row of parameters.def, in file order.
const std::vector<ParameterDef>& parameter_table();

// The parameters of one pipeline, in table order.
std::vector<ParameterInfo> parameters_of(std::string_view pipeline);

// Defaults overridden by `values` (which passed validate()), laid out by slot.
std::array<float, kMaxParameters> resolve_parameters(std::string_view pipeline,
                                                     const std::vector<protocol::Parameter>& values);

}  // namespace dn::pipelines
