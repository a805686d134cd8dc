// The analytic scene of dnsynth: a checkered ground plane, three spheres, a
// directional sun with hard shadows and a sky, seen by a camera that dollies
// sideways. Everything is exact, so G-buffers and motion are exact too.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace dn::synth {

struct Camera {
  glm::mat4 view;        // world -> camera, right-handed, looking down -Z
  glm::mat4 projection;  // glm::perspective (OpenGL clip space, NDC y up)
};

Camera camera_at(int frame, int width, int height);

// All planes interleaved per pixel, rows top-first.
struct FrameBuffers {
  int width = 0, height = 0;
  std::vector<float> noisy, clean, albedo, normal, depth, motion, position;
};

// Renders frame `frame`; noise is seeded by (seed, frame, pixel) so reruns are identical.
FrameBuffers render(int frame, int width, int height, uint32_t seed);

}  // namespace dn::synth
