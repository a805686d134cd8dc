// What a frame file's sample statistics are over, and the session parameter
// that tells the pipeline (docs/client.md, "Sample statistics").
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "presets.hpp"

namespace dn::cli {

// dnrender writes dn.stat_samples = "radiance" or "demodulated" with its
// stat_* layers. When the plan sends the statistics and the file says
// "demodulated", adds demodulated = 1 to `params` for a pipeline that has
// that parameter. Throws UsageError when --param demodulated contradicts the
// file, std::runtime_error when the attribute has another value or the
// pipeline needs the statistics but cannot be told they are demodulated.
// `pipeline` may be null (a server that announces no pipelines).
void apply_statistics_kind(const std::optional<std::string>& stat_samples, const std::string& path,
                           const std::vector<ResolvedChannel>& plan, const protocol::PipelineInfo* pipeline,
                           std::vector<protocol::Parameter>& params);

}  // namespace dn::cli
