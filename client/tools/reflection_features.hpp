// The reflection features (docs/protocol.md §7.5) of a renderer that has no
// such passes, derived from the ones it has (Blender Cycles: Position,
// Normal, the specular F0 and the Denoising Data passes, which follow near-specular
// bounces; docs/client.md "Reflection features from Cycles passes").
#pragma once

#include <vector>

#include "dn/image/exr_io.hpp"
#include "frame_source.hpp"
#include "presets.hpp"

namespace dn::cli {

// After apply_camera_conversions and apply_rough_guides, with the frame's
// camera, the plan's planes with these conversions (each loaded raw from
// the pass named):
//  - CyclesMirrorDirection (Normal): the view ray to the pixel's Position
//    (at 1 spp a random point of the pixel, which Normal shares) reflected
//    about the normal, unit length; 0 where the normal is 0.
//  - CyclesChainLength (Denoising Depth): the path's length past the
//    primary hit. Cycles adds, at every hit until the first non-specular
//    one, the segment's length from its start (the camera ray's starts at
//    the near plane) times the path's specular albedo so far (Cycles 3.x
//    film_write_denoising_features_surface): Denoising Depth
//    = (t1 - clip / cos) + a t2 for one mirror of specular albedo a, taken as
//    Schlick's Fresnel of the pixel's specular_f0 at the view angle, averaged
//    over RGB (1 without specular_f0; Cycles' GlossCol reads 1 on a Principled
//    metal mirror of colour 0.95, so it cannot serve). So
//    t2 = (DD + clip / cos - t1) / a, with the clip start the median of
//    (t1 - DD) cos over the pixels whose path stops at the primary hit; 0
//    where that is within 0.1 % of t1, a < 0.05, or anything is not finite.
//  - CyclesChainDepth (Denoising Depth): the virtual depth, (t1 + t2) cos.
//  - CyclesChainHit (Position): Position + direction x t2.
//  - CyclesCameraNormal (Denoising Normal, in Cycles' camera space: x right,
//    y up, z forward): to world space with the frame's view.
// The raw Denoising Depth is read from `exr`.
// Throws std::runtime_error naming the frame when it has no camera, in
// `syntax`'s words.
void derive_reflection_features(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan,
                                const dn::image::ExrReader& exr, const ChannelSyntax& syntax = kCliChannelSyntax);

}  // namespace dn::cli
