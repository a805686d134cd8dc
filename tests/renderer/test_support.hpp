// Small helpers shared by the renderer tests.
#pragma once

#include <glm/glm.hpp>

#include <vector>

#include "render.hpp"

namespace dn::render::test {

inline glm::vec3 at3(const std::vector<float>& plane, size_t i) {
  return {plane[3 * i], plane[3 * i + 1], plane[3 * i + 2]};
}

// Settings for a small, quick frame with only the planes a test needs.
inline RenderSettings small_settings(int width = 128, int height = 72, double spp = 1.0) {
  RenderSettings s;
  s.width = width;
  s.height = height;
  s.spp = spp;
  s.max_depth = 4;
  return s;
}

}  // namespace dn::render::test
