#include "camera.hpp"

#include "sampling.hpp"

namespace dn::render {

namespace {

// World-space direction (not normalized) through the continuous pixel (px, py).
glm::vec3 unprojected(const glm::mat4& inv_view, const glm::mat4& inv_projection, float px, float py, int width,
                      int height) {
  const glm::vec4 ndc(px / static_cast<float>(width) * 2.0f - 1.0f, 1.0f - py / static_cast<float>(height) * 2.0f,
                      1.0f, 1.0f);
  const glm::vec4 v = inv_projection * ndc;
  return glm::vec3(inv_view * glm::vec4(glm::vec3(v) / v.w, 0.0f));
}

}  // namespace

CameraRays::CameraRays(const Camera& camera, int width, int height) {
  const glm::mat4 inv_view = glm::inverse(camera.view), inv_projection = glm::inverse(camera.projection);
  eye_ = glm::vec3(inv_view[3]);
  origin_dir_ = unprojected(inv_view, inv_projection, 0.0f, 0.0f, width, height);
  step_x_ = unprojected(inv_view, inv_projection, 1.0f, 0.0f, width, height) - origin_dir_;
  step_y_ = unprojected(inv_view, inv_projection, 0.0f, 1.0f, width, height) - origin_dir_;
}

glm::vec3 CameraRays::direction(float px, float py) const {
  return glm::normalize(origin_dir_ + px * step_x_ + py * step_y_);
}

void CameraRays::direction_differentials(float px, float py, glm::vec3& ddx, glm::vec3& ddy) const {
  // d = u / |u| with u affine in (px, py): d' = (u' - d (d . u')) / |u|.
  const glm::vec3 u = origin_dir_ + px * step_x_ + py * step_y_;
  const float len = glm::length(u);
  const glm::vec3 d = u / len;
  ddx = (step_x_ - d * glm::dot(d, step_x_)) / len;
  ddy = (step_y_ - d * glm::dot(d, step_y_)) / len;
}

glm::vec2 project_to_pixel(const glm::mat4& view_projection, const glm::vec3& world, int width, int height) {
  const glm::vec4 clip = view_projection * glm::vec4(world, 1.0f);
  return {(clip.x / clip.w * 0.5f + 0.5f) * static_cast<float>(width),
          (0.5f - clip.y / clip.w * 0.5f) * static_cast<float>(height)};
}

glm::vec2 halton_jitter(int frame) {
  const uint32_t i = static_cast<uint32_t>((frame % 1024 + 1024) % 1024) + 1u;  // skip index 0, which is (0, 0)
  return {radical_inverse(i, 2) - 0.5f, radical_inverse(i, 3) - 0.5f};
}

}  // namespace dn::render
