// The SVGF chain's buffers, shared by its stage files (svgf_reproject.cpp,
// svgf_variance.cpp, svgf_atrous.cpp, svgf_remodulate.cpp, svgf_chain.cpp): their names and per-pixel sizes, the scratch each signal
// uses, and the binding helpers the stages share.
#pragma once

#include <cstdint>
#include <string>

#include "pipelines/graph.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines::svgf {

// The chain's buffers; each is sized by the DN_PER_PIXEL rules of the
// bindings that write it (their .pass files say what an element holds).
// A signal's colour and aux history (<history>_colour, _aux): one persistent
// copy, read by svgf_reproject and rewritten after it by svgf_variance and
// the feedback a-trous iteration. converge_still: a still pixel's running
// mean of its own samples, the M2 of their luminance and its change test,
// read and rewritten at p by svgf_reproject. With emission: a still pixel's
// running mean of its emission and its change test, read and rewritten at p
// by svgf_remodulate.
inline constexpr const char* kEmissionStill = "emission_still";
inline constexpr const char* kEmissionTest = "emission_test";
// a-trous register block: one invocation filters kAtrousBlock^2 pixels.
inline constexpr uint32_t kAtrousBlock = 4;

// Illumination ping-pong (scratch) of the first signal (a, b) and of the second (c, d).
inline constexpr const char* kIllumA = "svgf_illum_a";
inline constexpr const char* kIllumB = "svgf_illum_b";
inline constexpr const char* kIllumC = "svgf_illum_c";
inline constexpr const char* kIllumD = "svgf_illum_d";
// With the harm guard, the a-trous iterations after the first ping-pong
// between b and e (d and f), so a (c) keeps the variance pass's output.
inline constexpr const char* kIllumE = "svgf_illum_e";
inline constexpr const char* kIllumF = "svgf_illum_f";
// The first signal's guide and temporal; the second's temporal, and its
// guide when it has its own features, are these names + its suffix (both
// signals' are read by the joint a-trous passes).
inline constexpr const char* kGuide = "svgf_guide";
inline constexpr const char* kTemporal = "svgf_temporal";
inline constexpr const char* kTaaHistory = "svgf_taa";
// TAA: svgf_remodulate's vec4(current rgb, blend weight) and vec4(reprojected
// previous output, lag state), for svgf_taa: aliases of kTemporal and kGuide.
inline constexpr const char* kTaaCurrent = "svgf_taa_current";
inline constexpr const char* kTaaPrevious = "svgf_taa_previous";
// History clipping scratch, per pixel, shared by the clipped signals (each
// signal's reprojection reads it before the next signal's prefilter
// rewrites it): the demodulated current signal vec4(rgb, foreground), the
// horizontal pass's vec4(sum w c, sum w) and the box source
// vec4(prefiltered rgb, foreground), fp32.
inline constexpr const char* kClipCurrent = "svgf_clip_current";
inline constexpr const char* kClipPartial = "svgf_clip_partial";
inline constexpr const char* kClipNeighbourhood = "svgf_clip_neighbourhood";
// The depth and normal the chain's passes read: the planes, or the caller's
// buffers (SvgfVariant::primary_features).
std::string primary_depth(const SvgfVariant& v);
std::string primary_normal(const SvgfVariant& v);

// The buffer a chain reads its signal from: the plane, or with extra samples
// supersample_mix's result.
std::string signal_buffer(const SvgfVariant& v, const SvgfSignal& s);
// The sample_count plane as a pass's validity mask (MASKED).
void bind_validity_mask(PassSpec& pass);

// The scratch buffers of signal `index`.
struct SignalBuffers {
  std::string guide, temporal;
  std::string illum, other;  // the a-trous ping-pong: illum holds the reprojected signal
};
SignalBuffers signal_buffers(const SvgfVariant& v, size_t index);
// The joint passes' second-signal geometry (svgf_joint.glsl): its temporal
// scratch and, when it is not the first's, its own guide (SECOND_GUIDE).
void bind_second_geometry(PassSpec& pass, const SignalBuffers& first, const SignalBuffers& second);

// The still pixels' running means are kept where the harm guard reads them.
bool keeps_still_mean(const SvgfVariant& v);
// And of the emission, which is added back unfiltered.
bool keeps_still_emission(const SvgfVariant& v);
// A signal's still running mean (vec4(mean, n)), the M2 of its samples'
// luminance and its change test's state.
std::string still_mean_of(const std::string& history);
std::string still_m2_of(const std::string& history);
std::string still_change_of(const std::string& history);

}  // namespace dn::pipelines::svgf
