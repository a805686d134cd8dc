// Pixel masks for region_metrics (bench/region_metrics.cpp): where in a frame
// to measure a denoiser's error. One byte per pixel, 1 = in the region; rows
// top-first, as the EXR planes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dn::bench {

using Mask = std::vector<uint8_t>;

// Pixels whose roughness is within `tolerance` of one of `values` (the
// roughness-mapped surfaces of a dnrender scene).
Mask roughness_values_mask(const std::vector<float>& roughness, const std::vector<float>& values, float tolerance);

// Mirror and glossy surfaces: roughness below `below` (dnrender's roughness.Y is
// GGX alpha; background, Lambert and emitters read 1). NaN is not glossy.
Mask glossy_mask(const std::vector<float>& roughness, float below);

// Highlights: pixels whose linear luminance (Rec.709) in `rgb` (the reference)
// exceeds k times the frame's median luminance (its mean where the median is 0),
// dilated by `dilate` pixels (a (2 dilate + 1)^2 square).
Mask highlight_mask(const float* rgb, int width, int height, float k, int dilate);

// Disocclusions: pixels with no valid history in the previous frame. `motion`
// is interleaved XY in pixels to the previous frame (p_prev = p + mv, pixel
// centres at +0.5, docs/protocol.md 7.2/7.3). A pixel is disoccluded when
// p_prev lies outside the image, or when none of the 2x2 previous-frame pixels
// around p_prev (its bilinear footprint: those inside the image with a nonzero
// weight) has a depth within `relative_tolerance`
// of the pixel's own: |d_prev - d| <= tol * max(d, d_prev). Two infinite depths
// (background) agree; non-finite motion counts as disoccluded.
Mask disocclusion_mask(const std::vector<float>& motion, const std::vector<float>& depth,
                       const std::vector<float>& previous_depth, int width, int height, float relative_tolerance);

// The pixels within `radius` (Chebyshev distance) of a masked pixel.
Mask dilate(const Mask& mask, int width, int height, int radius);

size_t count(const Mask& mask);

}  // namespace dn::bench
