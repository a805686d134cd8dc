// High-sample references, rendered once and reused. Layout:
//   <cache>/<scene name>_<W>x<H>_spp<SPP>/ref_%04d.exr   (RGB float, R/G/B)
// A file that exists is reused without rendering; files are written under a
// temporary name and renamed, so an interrupted run leaves no partial file.
#pragma once

#include <string>

#include "scene.hpp"

namespace dn::render {

std::string reference_path(const std::string& cache_dir, int scene_id, int width, int height, int frame, int spp);

struct ReferenceRequest {
  int scene_id = 1;
  int width = 640, height = 360;
  int frame = 0;
  int spp = 256;
  uint32_t seed = 1;
  int threads = 0;
  std::string cache_dir = "out/cache";
};

// Returns the reference's path; `rendered` says whether it was rendered now (false: reused).
std::string ensure_reference(const Scene& scene, const ReferenceRequest& request, bool& rendered);

}  // namespace dn::render
