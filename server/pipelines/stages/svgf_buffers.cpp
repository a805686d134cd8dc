#include "pipelines/stages/svgf_buffers.hpp"

#include "pipelines/stages/supersample.hpp"

namespace dn::pipelines::svgf {

std::string primary_depth(const SvgfVariant& v) { return v.primary_features ? v.primary_features->depth : "depth"; }
std::string primary_normal(const SvgfVariant& v) { return v.primary_features ? v.primary_features->normal : "normal"; }

std::string signal_buffer(const SvgfVariant& v, const SvgfSignal& s) {
  return v.extra_samples ? mixed_signal(s.input) : s.input;
}

void bind_validity_mask(PassSpec& pass) {
  pass.bind("sample_count", "sample_count").set("MASKED", 1u);
}

SignalBuffers signal_buffers(const SvgfVariant& v, size_t index) {
  if (index == 0) return {kGuide, kTemporal, kIllumA, kIllumB};
  const SvgfSignal& s = v.signals[index];
  return {s.features ? kGuide + s.suffix : kGuide, kTemporal + s.suffix, kIllumC, kIllumD};
}

void bind_second_geometry(PassSpec& pass, const SignalBuffers& first, const SignalBuffers& second) {
  pass.bind("temporal2", second.temporal);
  if (second.guide != first.guide) pass.bind("guide2", second.guide).set("SECOND_GUIDE", 1u);
}

bool keeps_still_mean(const SvgfVariant& v) { return v.converge_still && v.harm_guard && v.iterations > 0; }
bool keeps_still_emission(const SvgfVariant& v) { return v.emission && keeps_still_mean(v); }
std::string still_mean_of(const std::string& history) { return history + "_still"; }
std::string still_m2_of(const std::string& history) { return history + "_still_m2"; }
std::string still_change_of(const std::string& history) { return history + "_still_change"; }

}  // namespace dn::pipelines::svgf
