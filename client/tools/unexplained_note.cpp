#include "unexplained_note.hpp"

#include <algorithm>

namespace dn::cli {
namespace {

constexpr const char* kKeepUnexplained = "keep_unexplained";

bool takes(const protocol::PipelineInfo* pipeline, const char* name) {
  return pipeline && std::any_of(pipeline->parameters.begin(), pipeline->parameters.end(),
                                 [&](const protocol::ParameterInfo& p) { return p.name == name; });
}

const protocol::Parameter* given(const std::vector<protocol::Parameter>& params, const char* name) {
  auto it = std::find_if(params.begin(), params.end(), [&](const protocol::Parameter& p) { return p.name == name; });
  return it == params.end() ? nullptr : &*it;
}

const ResolvedChannel* planned(const std::vector<ResolvedChannel>& plan, protocol::ChannelId id) {
  auto it = std::find_if(plan.begin(), plan.end(), [&](const ResolvedChannel& c) { return c.id == id; });
  return it == plan.end() ? nullptr : &*it;
}

}  // namespace

std::string unexplained_pixels_note(const Preset& preset, const std::vector<ResolvedChannel>& plan,
                                    const RoughGuidePlan* guides, const protocol::PipelineInfo* pipeline,
                                    const std::vector<protocol::Parameter>& params) {
  const ResolvedChannel* albedo = planned(plan, protocol::ChannelId::Albedo);
  const bool radiance = planned(plan, protocol::ChannelId::Radiance) != nullptr;
  if (preset.name != "cycles" || !albedo || !radiance || !takes(pipeline, kKeepUnexplained)) return {};
  if (const auto* p = given(params, kKeepUnexplained); p && p->value == 0.0) return {};
  // Measured on the project's Cycles room (docs/results.md, "Real client: Blender Cycles").
  const std::string cost = " (svgf on the project's Cycles room at 1 spp: relMSE 0.085 without, 0.051 with)";
  const std::string aov =
      "a Value AOV named Roughness (View Layer > Passes > Shader AOV, written by an AOV Output node in each material)";
  if (!albedo->past_specular)
    return "note: the albedo (" + albedo->describe() +
           ") is 0 on mirrors and metals, so those pixels are kept as rendered (noisy); to denoise mirrors, enable "
           "View Layer > Passes > Data > Denoising Data and add " + aov + cost;
  if (guides && !guides->key)
    return "note: without a Roughness AOV a mirror cannot be told from a glossy metal, so mirrors and metals keep "
           "the diffuse colour (0) and are shown as rendered (noisy); to denoise mirrors, add " + aov + cost;
  return {};
}

}  // namespace dn::cli
