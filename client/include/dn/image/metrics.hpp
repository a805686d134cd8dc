// Tone mapping and image-quality metrics shared by the dn tools, the benchmark
// and the example renderer. Images are interleaved RGB float, linear, rows
// top-first. Definitions (also in docs/client.md):
//  - rmse:           sqrt(mean over all pixels and components of (a - r)^2), linear HDR.
//  - relative_mse:   mean over pixels and components of (a - r)^2 / (r^2 + eps), eps = 0.01.
//  - ssim:           Wang et al. 2004 with an 11x11 Gaussian window (sigma 1.5),
//                    C1 = (0.01 L)^2, C2 = (0.03 L)^2, L = 1, averaged over every
//                    position where the window fits (MATLAB 'valid'); images
//                    smaller than the window use one window covering the image.
//  - ssim_tonemapped: ssim of display luma: exposure, tone map (ACES fitted by
//                    default), sRGB OETF, then Y' = 0.2126 R' + 0.7152 G' + 0.0722 B'.
//  - temporal_error: mean |Y(a) - Y(b)| of linear luminance, for consecutive
//                    frames of a fixed camera; with a mask, over the pixels whose
//                    mask byte is nonzero (NaN when there is none).
//  - noise_corrected_mse: mean of (a - r1)(a - r2) over two independent,
//                    unbiased references r1, r2 of the same image (and
//                    independent of a): an unbiased estimate of the MSE of a
//                    against the noise-free truth, E[(a-r1)(a-r2)] = (a-t)^2,
//                    where the plain MSE against r1 is (a-t)^2 + Var(r1). It can
//                    come out negative for an a within the references' noise of
//                    the truth; report it as is.
//  - noise_corrected_relative_mse: mean of (a - r1)(a - r2) / (((r1 + r2)/2)^2 + eps),
//                    eps = 0.01 as relative_mse.
//  - reference_noise_mse: mean((r1 - r2)^2) / 2, an unbiased estimate of the MSE of
//                    one reference against the truth (the floor the references'
//                    noise puts under the plain MSE; the mean of both references
//                    has half of it).
//  - flip_ldr, flip_hdr (LDR- and HDR-ꟻLIP): in dn/image/flip.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace dn::image {

enum class Tonemap {
  Aces,      // Narkowicz 2015 fit of the ACES filmic curve, per channel, clamped to [0,1]
  Reinhard,  // x / (1 + x), per channel
  Clamp,     // min(max(x, 0), 1): no tone curve
};

// Parses "aces" | "reinhard" | "clamp"; throws std::invalid_argument otherwise.
Tonemap parse_tonemap(std::string_view name);
const char* to_string(Tonemap t);

float tonemap(float x, Tonemap t);  // linear -> display-linear in [0,1]; NaN and negatives -> 0
float srgb_oetf(float x);            // display-linear [0,1] -> sRGB-encoded [0,1]
float linear_luminance(float r, float g, float b);  // Rec.709 / sRGB primaries

// Tone map + sRGB encode to 8 bit (rounded), for PNG output.
std::vector<uint8_t> to_srgb8(const float* rgb, size_t pixels, Tonemap t = Tonemap::Aces, float exposure = 1.0f);
// Display luma in [0,1] per pixel, as used by ssim_tonemapped.
std::vector<float> display_luma(const float* rgb, size_t pixels, Tonemap t = Tonemap::Aces, float exposure = 1.0f);

double rmse(const float* a, const float* ref, size_t count);
double relative_mse(const float* a, const float* ref, size_t count, double eps = 0.01);
// Error against the truth from two independent references (definitions above).
double noise_corrected_mse(const float* a, const float* ref1, const float* ref2, size_t count);
double noise_corrected_relative_mse(const float* a, const float* ref1, const float* ref2, size_t count,
                                    double eps = 0.01);
double reference_noise_mse(const float* ref1, const float* ref2, size_t count);

// Single-channel SSIM, values expected in [0, 1].
double ssim(const float* x, const float* y, int width, int height);
// The local SSIM of every window position of ssim() ('valid': (width - 10) x
// (height - 10), entry (i, j) is the window centred on pixel (i + 5, j + 5));
// empty for images smaller than the window.
std::vector<double> ssim_map(const float* x, const float* y, int width, int height);
double ssim_tonemapped(const float* rgb, const float* ref_rgb, int width, int height, Tonemap t = Tonemap::Aces,
                       float exposure = 1.0f);

double temporal_error(const float* rgb, const float* prev_rgb, size_t pixels);
double temporal_error(const float* rgb, const float* prev_rgb, const uint8_t* mask, size_t pixels);

}  // namespace dn::image
