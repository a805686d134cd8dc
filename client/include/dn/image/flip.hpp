// ꟻLIP image-difference metrics (part of the metrics of dn/image/metrics.hpp).
// Images are interleaved RGB float, rows top-first. Definitions (also in docs/client.md):
//  - flip_ldr:  LDR-ꟻLIP, Andersson et al., "FLIP: A Difference Evaluator for
//               Alternating Images", HPG 2020. Inputs are sRGB-encoded in [0,1]
//               (clamped), linearised and taken to YCxCz (D65). Colour: each channel
//               is filtered with the contrast sensitivity function of the viewing
//               condition (Gaussians a1 = (1, 1, 34.1), b1 = (0.0047, 0.0053, 0.04),
//               a2 = (0, 0, 13.5), b2 = (0, 0, 0.025) deg^2, radius
//               ceil(3 sqrt(max b / (2 pi^2)) ppd)), clamped to [0,1] in linear RGB,
//               taken to L*a*b* with the Hunt adjustment a, b *= 0.01 L, compared with
//               HyAB (|dL| + |(da, db)|), raised to qc = 0.7 and remapped: below
//               pc * cmax (pc = 0.4, cmax = HyAB(green, blue)^qc) linearly to
//               [0, pt = 0.95], above linearly to (0.95, 1]. Features: the normalised
//               Y of YCxCz ((Y + 16) / 116) convolved with the first (edges) and
//               second (points) derivatives of a Gaussian of sigma 0.5 * 0.082 * ppd
//               pixels (radius ceil(3 sigma); positive and negative weights each sum
//               to +-1); dF = (max(|edge_t - edge_r|, |point_t - point_r|) / sqrt 2)^qf,
//               qf = 0.5. Per pixel FLIP = dE^(1 - dF), in [0,1]; edges clamp.
//  - flip_hdr:  HDR-ꟻLIP, Andersson et al., "Visualizing Errors in Rendered High
//               Dynamic Range Images", Eurographics 2021 short paper. Inputs are
//               linear radiance. Exposures run from start = log2(x85 / Ymax) to
//               stop = log2(x85 / Ymedian) of the reference's luminances, where x85
//               is where flip_aces (the ACES fit with its 0.6 pre-exposure folded
//               in) reaches 0.85; N = max(2, ceil(stop - start)) evenly spaced
//               exposures (the reference implementation's count: ceil, not ceil + 1).
//               Each exposure e: x * 2^e, flip_aces, clamp to [0,1], then LDR-ꟻLIP
//               on those display-linear values; per pixel the maximum over exposures.
//  Both use 67.02 pixels per degree by default: 0.7 m from a 0.7 m wide
//  3840-pixel monitor. The metric value is the mean of the per-pixel map.
#pragma once

#include <cstddef>
#include <vector>

#include "dn/image/metrics.hpp"

namespace dn::image {

// Pixels per degree of visual angle: distance * (pixels / width) * pi / 180.
double flip_pixels_per_degree(double distance_m, double resolution_x, double monitor_width_m);
inline const double kFlipDefaultPpd = flip_pixels_per_degree(0.7, 3840.0, 0.7);

struct FlipResult {
  std::vector<float> map;  // per-pixel error in [0,1], width * height
  double mean = 0.0;       // mean of map (0 for an empty image)
};

// LDR-ꟻLIP of sRGB-encoded images (values clamped to [0,1]).
FlipResult flip_ldr(const float* srgb, const float* ref_srgb, int width, int height, double ppd = kFlipDefaultPpd);
// LDR-ꟻLIP of display-linear images in [0,1] (no sRGB decoding).
FlipResult flip_ldr_linear(const float* rgb, const float* ref_rgb, int width, int height,
                           double ppd = kFlipDefaultPpd);
// LDR-ꟻLIP of linear radiance after exposure and a dn tone map (metrics.hpp), the
// images ssim_tonemapped looks at.
FlipResult flip_ldr_tonemapped(const float* rgb, const float* ref_rgb, int width, int height,
                               Tonemap t = Tonemap::Aces, float exposure = 1.0f, double ppd = kFlipDefaultPpd);

// HDR-ꟻLIP's tone curve: (0.6^2 2.51 x^2 + 0.6 0.03 x) / (0.6^2 2.43 x^2 + 0.6 0.59 x + 0.14),
// not clamped; NaN and negatives give 0.
float flip_aces(float x);

struct FlipExposures {
  float start = 0.0f, stop = 0.0f;  // log2 exposure multipliers
  int count = 2;
};
// The automatic exposure range of a linear reference. A reference with no
// positive luminance gives start = stop = 0; a median of zero or less is
// replaced by the smallest positive luminance (the paper's formula is undefined there).
FlipExposures flip_hdr_exposures(const float* ref_rgb, size_t pixels);

// The exposures run on std::thread::hardware_concurrency() threads.
FlipResult flip_hdr(const float* rgb, const float* ref_rgb, int width, int height, double ppd = kFlipDefaultPpd);
FlipResult flip_hdr(const float* rgb, const float* ref_rgb, int width, int height, const FlipExposures& exposures,
                    double ppd = kFlipDefaultPpd);

}  // namespace dn::image
