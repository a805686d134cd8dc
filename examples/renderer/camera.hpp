// Pinhole camera in the protocol's conventions (docs/protocol.md §5.6.1):
// glm::lookAt / glm::perspective matrices (OpenGL clip space, NDC y up),
// pixels with y down, pixel (x, y) covering [x, x+1) x [y, y+1).
#pragma once

#include <glm/glm.hpp>

namespace dn::render {

struct Camera {
  glm::mat4 view{1.0f};        // world -> view, unjittered
  glm::mat4 projection{1.0f};  // view -> clip, unjittered
  glm::vec2 jitter{0.0f};      // this frame's sample offset from the pixel centre, pixels
};

// Precomputed inverses for generating rays.
class CameraRays {
 public:
  CameraRays(const Camera& camera, int width, int height);
  const glm::vec3& eye() const { return eye_; }
  // Unit world direction through the continuous pixel position (px, py).
  glm::vec3 direction(float px, float py) const;
  // The derivatives of direction(px, py) along px and py: the camera ray's
  // direction differentials (Igehy 1999; the origin, the eye, does not move).
  void direction_differentials(float px, float py, glm::vec3& ddx, glm::vec3& ddy) const;

 private:
  // direction(px, py) = normalize(origin_dir_ + px * step_x_ + py * step_y_): for a
  // perspective projection the unprojected far-plane point is affine in the pixel position.
  glm::vec3 eye_, origin_dir_, step_x_, step_y_;
};

// Continuous pixel position of a world point (y down); the camera's jitter is not applied.
glm::vec2 project_to_pixel(const glm::mat4& view_projection, const glm::vec3& world, int width, int height);

// The sub-pixel jitter of frame `frame`: Halton (2, 3), centred, in (-0.5, 0.5).
glm::vec2 halton_jitter(int frame);

}  // namespace dn::render
