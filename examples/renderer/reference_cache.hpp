// High-sample references, rendered once and reused. Layout:
//   <cache>/<scene name>_<W>x<H>_spp<SPP>_v<V>/ref_%04d.exr    (RGB float, R/G/B)
//   <cache>/<scene name>_<W>x<H>_spp<SPP>_v<V>/ref2_%04d.exr   the second reference
// V is kReferenceVersion. The second reference is rendered with a seed of its
// own (reference_seed), independent of the first, so that the mean of
// (x - r1)(x - r2) is an unbiased estimate of x's squared error.
// A file that exists is reused without rendering; files are written under a
// temporary name and renamed, so an interrupted run leaves no partial file.
#pragma once

#include <string>

#include "scene.hpp"

namespace dn::render {

// Bumped whenever a renderer change alters the rendered image, so that a cache
// never hands out references of an older renderer. 2: the checker cells no
// longer flip on surfaces at cell boundaries.
inline constexpr int kReferenceVersion = 2;

// index 1: ref_%04d.exr; 2: ref2_%04d.exr.
std::string reference_path(const std::string& cache_dir, int scene_id, int width, int height, int frame, int spp,
                           int index = 1);

// The seed reference `index` is rendered with: the request's seed for the first,
// a hash of it for the second (independent streams; the cache key has no seed).
uint32_t reference_seed(uint32_t seed, int index);

struct ReferenceRequest {
  int scene_id = 1;
  int width = 640, height = 360;
  int frame = 0;
  int spp = 256;
  uint32_t seed = 1;
  int index = 1;  // 1: the reference; 2: the second, independent one
  int threads = 0;
  std::string cache_dir;
};

// Where references go without --cache: $XDG_CACHE_HOME/dnrender, else
// $HOME/.cache/dnrender (the XDG default), never the current directory.
// Throws std::runtime_error when neither variable is set (null or empty).
std::string default_cache_dir(const char* xdg_cache_home, const char* home);

// Returns the reference's path; `rendered` says whether it was rendered now (false: reused).
std::string ensure_reference(const Scene& scene, const ReferenceRequest& request, bool& rendered);

}  // namespace dn::render
