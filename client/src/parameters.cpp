// Local parameter checks against the WELCOME 1.1 tables: the same rules the
// server applies (INVALID_PARAMETER), failing before anything is sent.
#include "dn/client/parameters.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "dn/client/error.hpp"

namespace dn::client {
namespace {

std::string names(const std::vector<protocol::ParameterInfo>& table) {
  std::string out;
  for (const auto& p : table) out += (out.empty() ? "" : ", ") + p.name;
  return out;
}

}  // namespace

std::string format_value(double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", value);
  return buf;
}

std::string format_range(const protocol::ParameterInfo& p) {
  return "[" + format_value(p.min_value) + ", " + format_value(p.max_value) + "]";
}

const std::vector<protocol::ParameterInfo>* find_parameters(const protocol::Welcome& welcome,
                                                            std::string_view pipeline) {
  if (!welcome.has_parameters) return nullptr;
  for (const auto& p : welcome.pipelines)
    if (p.name == pipeline) return &p.parameters;
  return nullptr;
}

DemodulatedStatistics demodulated_statistics(const protocol::PipelineInfo& pipeline) {
  for (const auto& p : pipeline.parameters)
    if (p.name == kDemodulatedParameter) return DemodulatedStatistics::ByParameter;
  const bool requires_statistics = pipeline.required_channels & protocol::channel_bit(protocol::ChannelId::StatCount);
  return requires_statistics ? DemodulatedStatistics::Unsupported : DemodulatedStatistics::NotRead;
}

void check_parameters(const protocol::Welcome& welcome, const SessionDesc& desc) {
  const auto* table = find_parameters(welcome, desc.pipeline);
  if (!table) return;
  const std::string pipeline = "pipeline '" + desc.pipeline + "'";
  for (size_t i = 0; i < desc.parameters.size(); ++i) {
    const protocol::Parameter& given = desc.parameters[i];
    const std::string field = "OPEN_SESSION.parameters[" + std::to_string(i) + "]";
    const protocol::ParameterInfo* info = nullptr;
    for (const auto& p : *table)
      if (p.name == given.name) info = &p;
    if (!info)
      throw Error::usage(protocol::ErrorCode::InvalidParameter, field + ".name",
                         table->empty() ? pipeline + " takes no parameters, but '" + given.name + "' was given"
                                        : pipeline + " has no parameter '" + given.name +
                                              "'; valid names: " + names(*table));
    for (size_t j = 0; j < i; ++j)
      if (desc.parameters[j].name == given.name)
        throw Error::usage(protocol::ErrorCode::InvalidParameter, field + ".name",
                           "parameter '" + given.name + "' is given twice");
    const std::string what = "parameter '" + given.name + "' of " + pipeline + " is " + format_value(given.value);
    if (!std::isfinite(given.value) || given.value < info->min_value || given.value > info->max_value)
      throw Error::usage(protocol::ErrorCode::InvalidParameter, field + ".value",
                         what + ", outside its range " + format_range(*info));
    if (info->integer && given.value != std::floor(given.value))
      throw Error::usage(protocol::ErrorCode::InvalidParameter, field + ".value",
                         what + ", but must be an integer in " + format_range(*info));
  }
}

}  // namespace dn::client
