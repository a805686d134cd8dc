// The SVGF chain's stages, each adding its passes to a graph over the
// buffers of svgf_buffers.hpp, in the order add_svgf_passes runs them.
#pragma once

#include <string>
#include <vector>

#include "pipelines/graph.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines::svgf {

// svgf_reproject.cpp: signal `index`'s reprojection (and history clipping):
// its temporal colour in its illum buffer, its temporal moments and length.
void add_reprojection(GraphSpec& g, const SvgfVariant& v, size_t index);
// svgf_variance.cpp: every signal's variance and history write-back.
void add_variance(GraphSpec& g, const SvgfVariant& v);
// svgf_atrous.cpp: the a-trous iterations; returns the buffer holding each
// signal's final illumination.
std::vector<std::string> add_atrous(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v);
// svgf_remodulate.cpp: the filtered signals times their modulators (and the
// guards), then with taa the final blend.
void add_remodulate(GraphSpec& g, const SvgfVariant& v, const std::vector<std::string>& results);

}  // namespace dn::pipelines::svgf
