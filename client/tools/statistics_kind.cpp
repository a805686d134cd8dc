#include "statistics_kind.hpp"

#include <algorithm>
#include <stdexcept>

#include "args.hpp"
#include "dn/client/parameters.hpp"

namespace dn::cli {

void apply_statistics_kind(const std::optional<std::string>& stat_samples, const std::string& path,
                           const std::vector<ResolvedChannel>& plan, const protocol::PipelineInfo* pipeline,
                           std::vector<protocol::Parameter>& params) {
  const bool sends = std::any_of(plan.begin(), plan.end(),
                                 [](const ResolvedChannel& c) { return c.id == protocol::ChannelId::StatCount; });
  if (!sends || !stat_samples) return;
  if (*stat_samples != "radiance" && *stat_samples != "demodulated")
    throw std::runtime_error(path + ": attribute dn.stat_samples is '" + *stat_samples +
                             "', expected 'radiance' or 'demodulated'");
  const bool demodulated = *stat_samples == "demodulated";
  const auto given = std::find_if(params.begin(), params.end(),
                                  [](const protocol::Parameter& p) { return p.name == client::kDemodulatedParameter; });
  if (given != params.end()) {
    if ((given->value != 0.0) != demodulated)
      throw UsageError("--param demodulated=" + std::to_string(static_cast<int>(given->value)) + " contradicts " +
                       path + ", whose statistics are over " + (demodulated ? "demodulated samples" : "radiance") +
                       " (dn.stat_samples)");
    return;
  }
  if (!demodulated || !pipeline) return;
  const client::DemodulatedStatistics how = client::demodulated_statistics(*pipeline);
  if (how == client::DemodulatedStatistics::Unsupported)
    throw std::runtime_error(path + " holds demodulated statistics (dn.stat_samples), but pipeline " +
                             pipeline->name + " has no parameter 'demodulated' to be told so");
  if (how == client::DemodulatedStatistics::ByParameter)
    params.push_back({std::string(client::kDemodulatedParameter), 1.0});
}

}  // namespace dn::cli
