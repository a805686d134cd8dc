#include "pipelines/parameters.hpp"

#include <stdexcept>
#include <string>

#include "pipelines/definitions.hpp"

namespace dn::pipelines {

const std::vector<ParameterDef>& parameter_table() {
  static const std::vector<ParameterDef> table = {
#define DN_PARAM(group, name, def, lo, hi, isint, desc) \
  ParameterDef{#group, ParameterInfo{#name, def, lo, hi, (isint) != 0, desc}, &Parameters::group##_##name},
#include "parameters.def"
#undef DN_PARAM
  };
  return table;
}

namespace {

// The rows of `groups`, group by group (checked: every group has rows, no
// name twice).
std::vector<const ParameterDef*> rows_of(ParameterGroups groups) {
  std::vector<const ParameterDef*> rows;
  for (std::string_view group : groups) {
    bool any = false;
    for (const auto& row : parameter_table()) {
      if (row.group != group) continue;
      any = true;
      for (const ParameterDef* other : rows)
        if (other->info.name == row.info.name)
          throw std::logic_error("parameter groups " + std::string(other->group) + " and " + std::string(group) +
                                 " both define " + row.info.name);
      rows.push_back(&row);
    }
    if (!any) throw std::logic_error("parameters.def has no group " + std::string(group));
  }
  return rows;
}

double value_of(const ParameterDef& row, const std::vector<protocol::Parameter>& values) {
  double v = row.info.default_value;
  for (const auto& p : values)
    if (p.name == row.info.name) v = p.value;
  return v;
}

}  // namespace

std::vector<ParameterInfo> parameters_of(ParameterGroups groups) {
  std::vector<ParameterInfo> out;
  for (const ParameterDef* row : rows_of(groups)) out.push_back(row->info);
  return out;
}

Parameters parameter_block(ParameterGroups groups, const std::vector<protocol::Parameter>& values) {
  Parameters out;
  for (const ParameterDef* row : rows_of(groups)) out.*(row->member) = static_cast<float>(value_of(*row, values));
  return out;
}

std::vector<float> resolve_parameters(std::string_view pipeline, const std::vector<protocol::Parameter>& values) {
  std::vector<float> out;
  const PipelineDefinition* def = find_definition(pipeline);
  if (!def) return out;
  for (const ParameterDef* row : rows_of(def->parameter_groups))
    out.push_back(static_cast<float>(value_of(*row, values)));
  return out;
}

}  // namespace dn::pipelines
