// progressive's sparse G-buffer (sparse_gbuffer): where sample_count is 0 the
// depth and normal planes hold nothing (a ray-traced G-buffer below one
// sample per pixel), so gbuffer_fill's 3x3 pull-push pyramid fills them from
// the sampled pixels before the SVGF chain reads them.
#pragma once

#include "pipelines/graph.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines {

// Adds the pyramid, its validity and the filled planes, and the passes that
// fill them (seed, pull to the coarsest level, push back down), reading the
// depth, normal and sample_count planes; returns the filled planes, for
// SvgfVariant::primary_features.
SignalFeatures add_gbuffer_fill(GraphSpec& g, const SessionConfig& config);

}  // namespace dn::pipelines
