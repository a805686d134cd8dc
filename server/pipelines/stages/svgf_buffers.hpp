// The SVGF chain's buffers as a variant has them (svgf_buffers.cpp): their
// names, which of them it keeps, and each signal's resolved SignalChain.
// Each is sized by the DN_PER_PIXEL rules of the bindings that write it
// (their .pass files say what an element holds).
#pragma once

#include <string>
#include <vector>

#include "pipelines/stages/svgf_chain.hpp"
#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

// The planes the chain reads (add_svgf_inputs); the Output plane is GraphSpec::kOutput.
inline constexpr const char* kNormalPlane = "normal";
inline constexpr const char* kDepthPlane = "depth";
inline constexpr const char* kMotionPlane = "motion";
inline constexpr const char* kEmissionPlane = "emission";
inline constexpr const char* kRoughnessPlane = "roughness";
inline constexpr const char* kSampleCountPlane = "sample_count";

// With emission and converge_still: a still pixel's running mean of its
// emission and its change test, read and rewritten at p by svgf_remodulate.
inline constexpr const char* kEmissionStill = "emission_still";
inline constexpr const char* kEmissionTest = "emission_test";
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
// guide when it has its own features, are these names + its suffix.
inline constexpr const char* kGuide = "svgf_guide";
inline constexpr const char* kTemporal = "svgf_temporal";
inline constexpr const char* kTaaHistory = "svgf_taa";
// TAA: svgf_remodulate's vec4(current rgb, blend weight) and vec4(reprojected
// previous output, lag state), for svgf_taa: aliases of kTemporal and kGuide,
// whose contents are dead once the a-trous passes are done.
inline constexpr const char* kTaaCurrent = "svgf_taa_current";
inline constexpr const char* kTaaPrevious = "svgf_taa_previous";
// History clipping scratch, shared by the clipped signals (each signal's
// reprojection reads it before the next signal's prefilter rewrites it).
inline constexpr const char* kClipCurrent = "svgf_clip_current";
inline constexpr const char* kClipPartial = "svgf_clip_partial";
inline constexpr const char* kClipNeighbourhood = "svgf_clip_neighbourhood";

// The depth the chain's passes read: the plane, or SvgfVariant::primary_features'.
std::string primary_depth(const SvgfVariant& v);
// Whether signal s's history is clipped, and whether any signal's is.
bool clipped(const SvgfVariant& v, const SvgfSignal& s);
bool clips(const SvgfVariant& v);
// The still pixels' running means are kept where the harm guard reads them,
// and with emission a still pixel's emission mean too.
bool keeps_still_mean(const SvgfVariant& v);
bool keeps_still_emission(const SvgfVariant& v);
// With the harm guard and more than one a-trous iteration, each signal's
// ping-pong partner after the first iteration (kIllumE, kIllumF); else none.
std::vector<std::string> guard_partners(const SvgfVariant& v);

// The buffers of every signal's chain. The SvgfVariant's depth and normal
// (primary_features) are read when called.
std::vector<SignalChain> signal_chains(const SvgfVariant& v);

}  // namespace dn::pipelines::svgf
