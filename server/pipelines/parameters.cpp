#include "pipelines/parameters.hpp"

#include <stdexcept>
#include <string>

namespace dn::pipelines {

const std::vector<ParameterDef>& parameter_table() {
  static const std::vector<ParameterDef> table = [] {
    std::vector<ParameterDef> rows = {
#define DN_PARAM(pipe, index, name, def, lo, hi, isint, desc) \
  ParameterDef{#pipe, index, ParameterInfo{#name, def, lo, hi, (isint) != 0, desc}},
#include "parameters.def"
#undef DN_PARAM
    };
    for (const auto& r : rows)
      if (r.index >= kMaxParameters) throw std::logic_error("parameters.def: index out of range for " + r.info.name);
    return rows;
  }();
  return table;
}

namespace {

// The parameters.def groups a pipeline takes: svgf-fb is svgf (same shaders,
// same slots) plus its own rows.
bool takes(std::string_view pipeline, std::string_view group) {
  if (pipeline == "svgf-fb") return group == "svgf" || group == "svgf_fb";
  return group == pipeline;
}

}  // namespace

std::vector<ParameterInfo> parameters_of(std::string_view pipeline) {
  std::vector<ParameterInfo> out;
  for (const auto& row : parameter_table())
    if (takes(pipeline, row.pipeline)) out.push_back(row.info);
  return out;
}

std::array<float, kMaxParameters> resolve_parameters(std::string_view pipeline,
                                                     const std::vector<protocol::Parameter>& values) {
  std::array<float, kMaxParameters> out{};
  for (const auto& row : parameter_table()) {
    if (!takes(pipeline, row.pipeline)) continue;
    double v = row.info.default_value;
    for (const auto& p : values)
      if (p.name == row.info.name) v = p.value;
    out[row.index] = static_cast<float>(v);
  }
  return out;
}

}  // namespace dn::pipelines
