// What the file's albedo means for the pipeline's keep_unexplained rule
// (docs/pipelines.md, "Do no harm"): a diffuse colour (Cycles' DiffCol) is 0
// on mirrors and metals, and the server keeps those pixels unfiltered; an
// albedo that follows specular bounces (Denoising Albedo) explains them.
#pragma once

#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "presets.hpp"

namespace dn::cli {

// The one-line note dn denoise prints for a Cycles radiance session whose
// pipeline keeps zero-albedo pixels raw (mirrors and metals stay noisy) when
// the planned albedo is the diffuse colour there: everywhere (no Denoising
// Data), or on metals (Denoising Data but `guides` without a roughness key).
// It names the passes that would explain them; empty otherwise.
std::string unexplained_pixels_note(const Preset& preset, const std::vector<ResolvedChannel>& plan,
                                    const RoughGuidePlan* guides, const protocol::PipelineInfo* pipeline,
                                    const std::vector<protocol::Parameter>& params);

}  // namespace dn::cli
