// stat: the statistical (Welch t-test) denoiser of paper 003 (Sakai et al.
// 2024; docs/pipelines.md "stat"): stat_prepare turns each pixel's sample
// statistics into a skew-corrected Box-Cox mean and the variance of that
// mean, stat_filter averages the raw means of the neighbours in a disc whose
// means the Welch test cannot tell apart from the pixel's.
#include "pipelines/stat/stat_passes.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  add_stat_inputs(g, config, /*with_statistics=*/true, g.parameters.stat_alpha);
  g.add_output(config);
  add_stat_filter(g, config, StatSources{"stat_count", "stat_mean", "stat_m2", "stat_m3", "radiance"});
  return g;
}

}  // namespace

PipelineDefinition stat_definition() {
  PipelineDefinition d;
  d.description.name = "stat";
  d.description.summary =
      "Statistical denoiser (paper 003): the raw means of the neighbours in a disc whose Box-Cox means a Welch t-test "
      "cannot tell apart from the pixel's, weighted by distance, albedo and normal.";
  d.description.required_channels = stat_channels();
  d.parameter_groups = {"stat"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  d.check_channels = check_statistics;
  return d;
}

}  // namespace dn::pipelines
