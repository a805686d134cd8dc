// The input forms of a pipeline: the channel sets a client can open it with,
// as far as they decide which kernels it compiles. Wire formats decide none
// (wire_format.hpp), so a pipeline's kernels are a function of its form: the
// warm-up compiles every one, and `dn pipelines` lists how many there are.
#pragma once

#include <cstdint>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// Every form prepare() accepts, as channel_bit masks: the signal form
// (radiance, or the split pair with each signal in radiance or lighting
// form), each optional channel the pipeline reads (emission, roughness,
// reflection_footprint, sample_count) present or not, the sample statistics
// as one group, 0 to 3 extra samples where the signal form takes them; plus
// every other channel the pipeline requires. passthrough reads radiance
// alone whatever else a client sends: its one form is radiance.
std::vector<uint64_t> input_forms(const PipelineDescription& pipeline);

// A session of `form` at width x height, every channel fp32.
SessionConfig form_config(const PipelineDescription& pipeline, uint64_t form, uint32_t width, uint32_t height);

// The distinct kernels (shader and specialization) of every form at its
// defaults, and a smallest-first set of forms whose graphs hold all of them
// (what the warm-up runs).
struct KernelVariants {
  size_t forms = 0;  // input_forms(pipeline).size()
  size_t kernels = 0;
  std::vector<uint64_t> covering_forms;
};
KernelVariants kernel_variants(const PipelineDescription& pipeline);

}  // namespace dn::pipelines
