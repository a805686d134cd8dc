// Renders one frame: noisy radiance (split into diffuse and specular) and the
// G-buffers the denoising pipelines take, on a pool of threads over tiles.
#pragma once

#include <cstdint>
#include <vector>

#include "camera.hpp"
#include "scene.hpp"

namespace dn::render {

// Which outputs to compute. Radiance is always computed; the rest costs time
// or memory, so each is asked for.
struct ChannelSet {
  bool split = true;          // diffuse, specular, emission
  bool gbuffer = true;        // albedo, specular_f0, roughness, normal, depth, position
  bool motion = true;
  bool sample_count = true;
  bool statistics = false;    // paper 003 Alg. 1 per pixel (stat_* planes)
  // With statistics: over each sample's radiance divided by the guarded
  // diffuse albedo of its own primary hit (docs/protocol.md §7.7).
  bool statistics_demodulated = false;
  bool reflection = false;    // reflection features, docs/protocol.md §7.5 (reflection_* planes)
  bool record_samples = false;  // every sample's radiance and primary-hit albedo, for tests
};

// Which pixels take the extra sample of a fractional spp n + f.
enum class SppSchedule {
  // For f = 1/k (k = 2 ... 1024): each pixel exactly once in every k consecutive
  // frames, in a seed-dependent ordered-dither pattern (samples_for_pixel);
  // any other f falls back to Random.
  Stratified,
  // Each pixel independently with probability f every frame.
  Random,
};

struct RenderSettings {
  int width = 640, height = 360;
  double spp = 1.0;       // < 1: pixels sampled with this rate; fractions add a sample likewise (spp_schedule)
  SppSchedule spp_schedule = SppSchedule::Stratified;
  uint32_t seed = 1;
  bool jitter = false;    // per-frame Halton sub-pixel camera jitter
  // Albedo, specular_f0, roughness and normal are pixel-footprint averages over a
  // gbuffer_grid x gbuffer_grid jittered stratified grid of G-buffer-only rays
  // (primary hit + material, no path). 0: point-sampled from the radiance sample 0 ray.
  int gbuffer_grid = 4;
  // Guide-ray supersampling (paper 001 §5, docs/protocol.md §7.6): with spp 1,
  // this many further primary samples per pixel (0 to 3), each at a uniform
  // random position in the pixel, with its own path and primary hit
  // (FrameBuffers::extra); the ordinary planes stay sample 0's.
  int extra_samples = 0;
  int max_depth = 8;      // path vertices after the primary hit
  bool next_event = true; // false: BSDF sampling only (tests compare the two estimators)
  int threads = 0;        // 0: hardware concurrency
  int tile = 16;
  ChannelSet channels;
};

// All planes interleaved per pixel, rows top-first; a plane not asked for is empty.
struct FrameBuffers {
  int width = 0, height = 0;
  std::vector<float> radiance, diffuse, specular, emission;  // 3
  std::vector<float> albedo, specular_f0, normal, position;  // 3
  std::vector<float> roughness, depth;                        // 1
  std::vector<float> motion;                                  // 2
  std::vector<float> sample_count;                            // 1
  // Statistics of the samples x of each colour channel, Box-Cox lambda = 1/2:
  // x' = 2 sqrt(x) - 2. Count n, mean of x', the sums M2 = sum (x' - mean)^2
  // and M3 = sum (x' - mean)^3 as Alg. 1 accumulates them (central moments
  // are M/n), and the mean of the raw x.
  std::vector<float> stat_count;                              // 1
  std::vector<float> stat_mean, stat_m2, stat_m3, stat_raw_mean;  // 3
  bool statistics_demodulated = false;  // of radiance / guarded primary-hit albedo (ChannelSet)
  // The reflection features (protocol channels 15-21, docs/protocol.md §7.5),
  // point-sampled along the sample 0 ray like depth and position. Mirror-class
  // pixels get all seven, glossy-class pixels direction, distance and
  // footprint (the representative ray), every other pixel zeros.
  std::vector<float> reflection_position, reflection_albedo, reflection_normal, reflection_direction;  // 3
  std::vector<float> reflection_depth, reflection_distance, reflection_footprint;                      // 1
  // RenderSettings::extra_samples: per extra sample its radiance (and the
  // split's diffuse and specular), the facing normal and view depth of its
  // primary hit (0 and +inf on a miss) and its position minus the jittered
  // pixel centre (protocol channels sample<j>_*).
  struct ExtraSample {
    std::vector<float> radiance, diffuse, specular, normal;  // 3
    std::vector<float> depth;                                // 1
    std::vector<float> offset;                               // 2
  };
  std::vector<ExtraSample> extra;
  std::vector<float> samples;  // record_samples: samples_stride RGB samples per pixel, unused slots 0
  std::vector<float> sample_albedo;  // record_samples: each sample's primary-hit diffuse albedo (0: a miss)
  int samples_stride = 0;
  uint64_t rays = 0;  // Embree rays traced (rtcIntersect1 + rtcOccluded1)
  double seconds = 0.0;
};

// Number of samples pixel `pixel` (= y * width + x) takes this frame for a (possibly
// fractional) spp: floor(spp), plus one if `schedule` gives the pixel the fraction's
// extra sample this frame. A pure function of its arguments.
// Stratified, fraction 1/k: the extra sample at the frames t with (t + offset(x, y)) mod k == 0,
// offset from a seed-shifted and -scrambled Bayer tile (k a power of two) or rank-1 lattice.
// Random (or any other fraction): with probability of the fraction, from a hash of (seed, frame, pixel).
int samples_for_pixel(double spp, uint32_t seed, int frame, uint32_t pixel, int width,
                      SppSchedule schedule = SppSchedule::Stratified);

// The stratified schedule's period: k when spp's fraction is 1/k (k = 2 ... 1024, to a
// relative 1e-6, so 0.3333333 is 1/3 and 0.333 is not), else 0 (the random rule).
int stratified_period(double spp);

FrameBuffers render_frame(const Scene& scene, const Camera& camera, const Camera& previous, int frame,
                          const RenderSettings& settings);
// The same into `fb`, reusing its memory (a sequence then never page-faults fresh planes in).
void render_frame_into(const Scene& scene, const Camera& camera, const Camera& previous, int frame,
                       const RenderSettings& settings, FrameBuffers& fb);

// Convenience for the built-in scenes: camera path, jitter when asked.
Camera frame_camera(int scene_id, int frame, const RenderSettings& settings);

// The world position seen through a continuous pixel position, or nothing
// for the background; for tests of the motion vectors.
bool primary_position(const Scene& scene, const Camera& camera, int width, int height, float px, float py,
                      glm::vec3& position);

}  // namespace dn::render
