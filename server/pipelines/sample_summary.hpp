// RESULT.samples (docs/protocol.md §5.7): how many input frames each pixel's
// output rests on, summarised over the frame by the sample_summary pass into
// a small Readback buffer the host decodes after every frame.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "pipelines/graph.hpp"

namespace dn::pipelines {

// The Readback buffer's name: GraphPipeline::samples() decodes it when the graph has it.
inline constexpr const char* kSampleSummary = "sample_summary";

// Appends the pass that summarises `history` (a vec4(rgb, length) colour
// history) and, when not empty, `still` (a still pixel's vec4(mean, samples)),
// and the Readback buffer it writes. Call after the passes that write them.
void add_sample_summary(GraphSpec& g, const std::string& history, const std::string& still = {});
// The same over a plane of one float count per pixel.
void add_sample_count_summary(GraphSpec& g, const std::string& counts);

// Histogram bins (shaders/include/sample_bins.glsl): a count's bin, and the
// smallest count in a bin.
uint32_t sample_bin(uint32_t count);
uint32_t sample_bin_floor(uint32_t bin);
inline constexpr uint32_t kSampleBins = 32 + 16 * 16;
// The Readback buffer's bytes: the minimum's word and the bins.
inline constexpr uint64_t kSampleSummaryBytes = 4 * (1 + uint64_t{kSampleBins});

// The counts from the buffer's bytes (4 * (1 + kSampleBins)); nullopt when
// no pixel was counted.
std::optional<pipelines::SampleCounts> decode_sample_summary(std::span<const uint8_t> bytes);

}  // namespace dn::pipelines
