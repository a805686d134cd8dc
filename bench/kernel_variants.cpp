// How many compiled kernels each pipeline can need: every input form the
// warm-up opens (PipelineBuilder::warm_up_configs), with each plane and the
// output in fp32 or fp16 independently, against the kernels the warm-up's
// all-fp32 and all-fp16 configurations compile. A kernel is a shader with
// one specialization (pass.hpp: equal specializations share a kernel). No
// device: the graphs are pure data.
//   kernel_variants            prints the table (docs/results.md, "Kernel variants")
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "pipelines/graph.hpp"
#include "pipelines/registry.hpp"
#include "server/session/pipeline_builder.hpp"

namespace {

using namespace dn;
using Kernel = std::pair<std::string, std::vector<gpu::SpecConstant>>;

// The kernels of one configuration's graph (nothing when it does not validate).
void add_kernels(const pipelines::SessionConfig& config, std::set<Kernel>& out) {
  auto prepared = pipelines::prepare(config);
  if (!std::holds_alternative<pipelines::PreparedPipeline>(prepared)) return;
  for (const auto& pass : std::get<pipelines::PreparedPipeline>(prepared).graph().passes)
    out.insert({std::string(pass.shader()), pass.specialization(0)});
}

}  // namespace

int main() {
  struct Counts {
    std::set<Kernel> warm_up, all;
    size_t forms = 0, combinations = 0;
  };
  std::map<std::string, Counts> by_pipeline;
  std::vector<std::string> order;
  for (const auto& config : server::PipelineBuilder::warm_up_configs()) {
    if (!by_pipeline.count(config.pipeline)) order.push_back(config.pipeline);
    Counts& c = by_pipeline[config.pipeline];
    add_kernels(config, c.warm_up);
    if (config.output_format != protocol::Format::F32) continue;  // the combinations start from each fp32 form
    ++c.forms;
    // Bit i of `choice`: plane i (sample statistics stay fp32) or, last, the output in fp16.
    std::vector<size_t> free;
    for (size_t i = 0; i < config.channels.size(); ++i)
      if (!protocol::is_sample_statistic(config.channels[i].id)) free.push_back(i);
    for (uint64_t choice = 0; choice < (uint64_t{1} << (free.size() + 1)); ++choice) {
      pipelines::SessionConfig variant = config;
      for (size_t b = 0; b < free.size(); ++b)
        if (choice >> b & 1) variant.channels[free[b]].format = protocol::Format::F16;
      if (choice >> free.size() & 1) variant.output_format = protocol::Format::F16;
      add_kernels(variant, c.all);
      ++c.combinations;
    }
  }
  std::printf("| pipeline | input forms | format combinations | kernels the warm-up compiles | kernels over every combination |\n");
  std::printf("|---|---|---|---|---|\n");
  for (const auto& name : order) {
    const Counts& c = by_pipeline[name];
    std::printf("| %s | %zu | %zu | %zu | %zu |\n", name.c_str(), c.forms, c.combinations, c.warm_up.size(),
                c.all.size());
  }
  return 0;
}
