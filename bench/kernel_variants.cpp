// How many compiled kernels each pipeline can need: every input form
// (pipelines/input_forms.hpp) with every plane and the output in fp32, then
// each form again with one plane (or the output) at a time in fp16 and with
// all of them in fp16, against the kernels of the configurations the warm-up
// runs (PipelineBuilder::warm_up_configs). A kernel is a shader with one
// specialization (pass.hpp: equal specializations share a kernel). No
// device: the graphs are pure data.
//   kernel_variants            prints the table (docs/results.md, "Kernel variants")
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "pipelines/graph.hpp"
#include "pipelines/input_forms.hpp"
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
  std::map<std::string, std::set<Kernel>> warm_up;
  std::map<std::string, size_t> warm_up_configs;
  for (const auto& config : server::PipelineBuilder::warm_up_configs()) {
    add_kernels(config, warm_up[config.pipeline]);
    ++warm_up_configs[config.pipeline];
  }
  std::printf("| pipeline | input forms | kernels over every form, fp32 | format mixes tried | kernels over every mix | "
              "configurations the warm-up runs | kernels the warm-up compiles |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const auto& p : pipelines::available_pipelines()) {
    const auto forms = pipelines::input_forms(p);
    std::set<Kernel> fp32, mixed;
    size_t mixes = 0;
    for (const uint64_t form : forms) {
      const auto config = pipelines::form_config(p, form, 256, 144);
      add_kernels(config, fp32);
      // Bit i of `choice` (one bit set, or all): plane i (sample statistics stay fp32) or, last, the output in fp16.
      std::vector<size_t> free;
      for (size_t i = 0; i < config.channels.size(); ++i)
        if (!protocol::is_sample_statistic(config.channels[i].id)) free.push_back(i);
      std::vector<uint64_t> choices = {(uint64_t{1} << (free.size() + 1)) - 1};
      for (size_t b = 0; b <= free.size(); ++b) choices.push_back(uint64_t{1} << b);
      for (const uint64_t choice : choices) {
        pipelines::SessionConfig variant = config;
        for (size_t b = 0; b < free.size(); ++b)
          if (choice >> b & 1) variant.channels[free[b]].format = protocol::Format::F16;
        if (choice >> free.size() & 1) variant.output_format = protocol::Format::F16;
        add_kernels(variant, mixed);
        ++mixes;
      }
    }
    mixed.insert(fp32.begin(), fp32.end());
    std::printf("| %s | %zu | %zu | %zu | %zu | %zu | %zu |\n", p.name.c_str(), forms.size(), fp32.size(), mixes,
                mixed.size(), warm_up_configs[p.name], warm_up[p.name].size());
  }
  return 0;
}
