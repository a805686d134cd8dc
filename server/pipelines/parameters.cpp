#include "pipelines/parameters.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "pipelines/definitions.hpp"

namespace dn::pipelines {

const std::vector<ParameterDef>& parameter_table() {
  static const std::vector<ParameterDef> table = {
#define DN_PARAM(group, name, def, lo, hi, isint, desc) \
  ParameterDef{#group, ParameterInfo{#name, def, lo, hi, (isint) != 0, desc}, &Parameters::group##_##name},
#include "generated/parameters.def"
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

// A row's information with the pipeline's own default, if it has one.
ParameterInfo info_of(const ParameterDef& row, const ParameterDefaults& defaults) {
  ParameterInfo info = row.info;
  for (const auto& d : defaults)
    if (d.name == info.name) info.default_value = d.value;
  return info;
}

// Every pipeline default names one of the rows and is a value validate() would accept.
void check_defaults(const std::vector<const ParameterDef*>& rows, const ParameterDefaults& defaults) {
  for (const auto& d : defaults) {
    const ParameterDef* row = nullptr;
    for (const ParameterDef* r : rows)
      if (r->info.name == d.name) row = r;
    if (!row) throw std::logic_error("pipeline default for " + d.name + ": no such parameter in its groups");
    const ParameterInfo& i = row->info;
    if (!(d.value >= i.min_value && d.value <= i.max_value) || (i.integer && d.value != std::floor(d.value)))
      throw std::logic_error("pipeline default for " + d.name + ": " + std::to_string(d.value) + " is not valid");
  }
}

double value_of(const ParameterDef& row, const std::vector<ParameterValue>& values,
                const ParameterDefaults& defaults) {
  double v = info_of(row, defaults).default_value;
  for (const auto& p : values)
    if (p.name == row.info.name) v = p.value;
  return v;
}

}  // namespace

std::vector<ParameterInfo> parameters_of(ParameterGroups groups, const ParameterDefaults& defaults) {
  const std::vector<const ParameterDef*> rows = rows_of(groups);
  check_defaults(rows, defaults);
  std::vector<ParameterInfo> out;
  for (const ParameterDef* row : rows) out.push_back(info_of(*row, defaults));
  return out;
}

Parameters parameter_block(ParameterGroups groups, const std::vector<ParameterValue>& values,
                           const ParameterDefaults& defaults) {
  Parameters out;
  for (const ParameterDef* row : rows_of(groups))
    out.*(row->member) = static_cast<float>(value_of(*row, values, defaults));
  return out;
}

std::vector<float> resolve_parameters(std::string_view pipeline, const std::vector<ParameterValue>& values) {
  std::vector<float> out;
  const PipelineDefinition* def = find_definition(pipeline);
  if (!def) return out;
  for (const ParameterDef* row : rows_of(def->parameter_groups))
    out.push_back(static_cast<float>(value_of(*row, values, def->parameter_defaults)));
  return out;
}

}  // namespace dn::pipelines
