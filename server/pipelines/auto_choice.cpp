#include "pipelines/auto_choice.hpp"

#include <optional>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/stages/split_signals.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

uint64_t mask_of(const std::vector<ChannelId>& ids) {
  uint64_t m = 0;
  for (ChannelId id : ids) m |= protocol::channel_bit(id);
  return m;
}

// The declared channels `desc` reads. A pipeline that takes radiance or the
// split pair (svgf) reads radiance when both came: one signal, one filter.
std::vector<InputChannel> channels_read(const SessionConfig& declared, const PipelineDescription& desc) {
  uint64_t takes = desc.required_channels | desc.optional_channels;
  if ((takes & protocol::channel_bit(ChannelId::Radiance)) && has_channel(declared, ChannelId::Radiance))
    takes &= ~split_channel_bits();
  std::vector<InputChannel> read;
  for (const auto& c : declared.channels)
    if (takes & protocol::channel_bit(c.id)) read.push_back(c);
  return read;
}

}  // namespace

const std::vector<AutoRule>& auto_rules() {
  static const std::vector<AutoRule> rules = {
      {"progressive", {ChannelId::SampleCount}, "sample_count: fewer than one sample per pixel"},
      {"stat-temporal", {ChannelId::StatCount, ChannelId::Motion}, "sample statistics and motion"},
      {"stat", {ChannelId::StatCount}, "sample statistics of one frame"},
      {"reflect", {ChannelId::ReflectionPosition}, "reflection features"},
      {"svgf-fb", {ChannelId::Roughness, ChannelId::SpecularF0}, "split lighting with roughness and specular_f0"},
      {"svgf", {ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion},
       "albedo, normal, depth and motion"},
      {"image", {}, "one frame at a time (no motion with albedo, normal and depth)"},
  };
  return rules;
}

PipelineDescription auto_description() {
  PipelineDescription d;
  d.name = std::string(kAutoPipeline);
  d.summary =
      "Chooses the pipeline from the declared channels (docs/pipelines.md \"auto\"); SESSION names the choice and "
      "why. Takes no parameters: name a pipeline to tune it.";
  for (const AutoRule& rule : auto_rules())
    if (const PipelineDefinition* def = find_definition(rule.pipeline))
      d.optional_channels |= def->description.required_channels | def->description.optional_channels;
  return d;
}

std::variant<PreparedPipeline, ConfigError> prepare_auto(const SessionConfig& declared) {
  if (auto err = check_declaration(declared, auto_description())) return *err;
  if (!declared.parameters.empty())
    return ConfigError{ConfigProblem::InvalidParameter, "parameters[0].name",
                       "pipeline auto takes no parameters; name the pipeline to set \"" +
                           declared.parameters[0].name + "\""};
  const uint64_t have = channel_mask(declared);
  std::optional<ConfigError> last;
  for (const AutoRule& rule : auto_rules()) {
    const PipelineDefinition* def = find_definition(rule.pipeline);
    if (!def || (mask_of(rule.signal) & ~have)) continue;
    SessionConfig candidate = declared;
    candidate.pipeline = std::string(rule.pipeline);
    candidate.channels = channels_read(declared, def->description);
    auto prepared = prepare(candidate);
    if (auto* err = std::get_if<ConfigError>(&prepared)) {
      if (err->problem == ConfigProblem::LimitExceeded) return *err;  // too large for any pipeline: say so
      last = *err;
      continue;
    }
    PreparedPipeline chosen = std::get<PreparedPipeline>(std::move(prepared));
    chosen.declared_channels_ = declared.channels;
    chosen.choice_reason_ = std::string(rule.reason);
    if (const uint64_t unused = have & ~channel_mask(candidate))
      chosen.choice_reason_ += "; not used: " + channel_list(unused);
    return chosen;
  }
  return ConfigError{ConfigProblem::MissingChannel, "channels",
                     "auto found no pipeline for channels " + channel_list(have) +
                         (last ? " (last tried: " + last->message + ")" : "")};
}

}  // namespace dn::pipelines
