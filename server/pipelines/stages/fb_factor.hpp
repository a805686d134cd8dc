// The F_beta factor pass (server/pipelines/stages/svgf_fb_factor.comp) that svgf-fb and
// reflect put in front of their SVGF chains: F_beta = F0 * A + B per pixel
// from the context's F_beta table (fb_lut.hpp), the specular modulator.
#pragma once

#include <string>

#include "pipelines/graph.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// The context-wide table the pass binds (a pipeline lists it in its shared_resources).
extern const SharedResourceDecl kFbLutResource;

// Adds the specular_f0 input (roughness, normal and depth must be inputs
// already), the shared table, a scratch buffer `factor` (rgb fp32 per pixel)
// and the pass that fills it.
void add_fb_factor(GraphSpec& g, const SessionConfig& config, const std::string& factor);

}  // namespace dn::pipelines
