// "auto": the server chooses the pipeline from the channels a session
// declares, so a renderer sends what it has and need not know the pipelines.
// One ordered table (auto_rules(), docs/pipelines.md "auto"): the first rule
// whose signal channels are all declared and whose pipeline accepts the
// declared channels it reads wins; the channels it does not read are named in
// the reason and dropped from each frame.
#pragma once

#include <string_view>
#include <variant>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

inline constexpr std::string_view kAutoPipeline = "auto";

struct AutoRule {
  std::string_view pipeline;
  std::vector<protocol::ChannelId> signal;  // all declared: the rule applies
  std::string_view reason;                  // why, as SESSION's pipeline_reason begins
};

// The table, first match wins; its last rule has no signal.
const std::vector<AutoRule>& auto_rules();

// How WELCOME announces "auto": no required channel (the choice decides),
// every channel a rule's pipeline takes, and no parameters (a session that
// tunes a pipeline names it).
PipelineDescription auto_description();

// prepare() of a SessionConfig whose pipeline is "auto": the chosen
// pipeline's PreparedPipeline with choice_reason() and declared_channels()
// set, or why no pipeline fits (the last candidate's error, or the first
// declaration error, as for a named pipeline).
std::variant<PreparedPipeline, ConfigError> prepare_auto(const SessionConfig& declared);

}  // namespace dn::pipelines
