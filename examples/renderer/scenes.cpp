#include "scenes.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <stdexcept>

namespace dn::render {
namespace {

using glm::vec3;

Material diffuse(vec3 albedo) {
  Material m;
  m.kind = MaterialKind::Diffuse;
  m.albedo = albedo;
  return m;
}
Material metal(vec3 f0, float alpha) {
  Material m;
  m.kind = MaterialKind::Metal;
  m.albedo = f0;
  m.alpha = alpha;
  return m;
}
Material coated(vec3 albedo, float alpha) {
  Material m;
  m.kind = MaterialKind::Coated;
  m.albedo = albedo;
  m.alpha = alpha;
  return m;
}
Material emitter(vec3 radiance) {
  Material m;
  m.kind = MaterialKind::Emitter;
  m.emission = radiance;
  return m;
}

// Six inward-facing walls of an axis-aligned room (materials: floor, ceiling, walls -x, +x, -z, +z).
void add_room(Scene& s, vec3 lo, vec3 hi, int floor, int ceiling, int wx0, int wx1, int wz0, int wz1) {
  const vec3 d = hi - lo;
  s.add_quad(lo, {0, 0, d.z}, {d.x, 0, 0}, floor);
  s.add_quad({lo.x, hi.y, lo.z}, {d.x, 0, 0}, {0, 0, d.z}, ceiling);
  if (wx0 >= 0) s.add_quad(lo, {0, d.y, 0}, {0, 0, d.z}, wx0);
  if (wx1 >= 0) s.add_quad({hi.x, lo.y, lo.z}, {0, 0, d.z}, {0, d.y, 0}, wx1);
  if (wz0 >= 0) s.add_quad(lo, {d.x, 0, 0}, {0, d.y, 0}, wz0);
  if (wz1 >= 0) s.add_quad({lo.x, lo.y, hi.z}, {0, d.y, 0}, {d.x, 0, 0}, wz1);
}

std::unique_ptr<Scene> room() {
  auto s = std::make_unique<Scene>();
  Material floor = coated({0.65f, 0.62f, 0.58f}, 0.04f);
  floor.albedo_map = Pattern::Checker;
  floor.albedo2 = {0.18f, 0.2f, 0.25f};
  floor.roughness_map = Pattern::Stripes;
  floor.alpha2 = 0.35f;
  floor.map_scale = 1.0f;
  const int fl = s->add_material(floor);
  const int white = s->add_material(diffuse({0.7f, 0.7f, 0.7f}));
  const int red = s->add_material(diffuse({0.6f, 0.1f, 0.08f}));
  const int green = s->add_material(diffuse({0.12f, 0.45f, 0.15f}));
  add_room(*s, {-4, 0, -4}, {4, 4, 4}, fl, white, red, green, white, white);
  s->add_quad({-1.0f, 3.98f, -1.0f}, {2, 0, 0}, {0, 0, 2}, s->add_material(emitter(vec3(12.0f))));
  s->add_sphere({-1.5f, 1.0f, -1.2f}, 1.0f, s->add_material(metal(vec3(0.95f), 0.0f)));             // mirror
  s->add_sphere({1.7f, 0.8f, -0.6f}, 0.8f, s->add_material(metal({1.0f, 0.78f, 0.34f}, 0.25f)));   // glossy gold
  s->add_box({-0.4f, 0.0f, 0.8f}, {0.6f, 1.2f, 1.8f}, s->add_material(diffuse({0.7f, 0.5f, 0.3f})));
  s->add_sphere({0.3f, 0.45f, -2.6f}, 0.45f, s->add_material(diffuse({0.2f, 0.3f, 0.7f})));
  s->add_sphere({1.9f, 0.35f, 1.4f}, 0.35f, s->add_material(coated({0.8f, 0.8f, 0.75f}, 0.15f)));
  return s;
}

std::unique_ptr<Scene> pillars() {
  auto s = std::make_unique<Scene>();
  Material floor = diffuse({0.55f, 0.55f, 0.5f});
  floor.albedo_map = Pattern::Tiles;
  floor.albedo2 = {0.1f, 0.1f, 0.1f};
  const int fl = s->add_material(floor);
  Material wall = diffuse({0.8f, 0.8f, 0.75f});
  wall.albedo_map = Pattern::Checker;
  wall.albedo2 = {0.15f, 0.25f, 0.55f};
  const int back = s->add_material(wall);
  const int white = s->add_material(diffuse(vec3(0.8f)));
  const int stone = s->add_material(coated({0.5f, 0.45f, 0.4f}, 0.3f));
  add_room(*s, {-20, 0, -8}, {20, 5, 6}, fl, white, -1, -1, back, -1);
  for (int k = 0; k < 16; ++k) {
    const float x = -12.0f + 1.6f * static_cast<float>(k);
    s->add_box({x - 0.25f, 0.0f, -2.25f}, {x + 0.25f, 5.0f, -1.75f}, stone);
  }
  // A cove light facing the ceiling: everything else sees only bounced light.
  s->add_quad({-20.0f, 4.2f, 2.0f}, {0, 0, 0.8f}, {40, 0, 0}, s->add_material(emitter(vec3(5.0f))));
  return s;
}

std::unique_ptr<Scene> gap() {
  auto s = std::make_unique<Scene>();
  const int fl = s->add_material(coated({0.5f, 0.45f, 0.4f}, 0.3f));
  const int wall = s->add_material(diffuse(vec3(0.6f)));
  add_room(*s, {-3, 0, -3}, {3, 3, 3}, fl, wall, wall, -1, wall, wall);
  // The +x wall, with a 0.3 wide vertical slit.
  s->add_box({3.0f, 0.0f, -3.0f}, {3.2f, 3.0f, -0.15f}, wall);
  s->add_box({3.0f, 0.0f, 0.15f}, {3.2f, 3.0f, 3.0f}, wall);
  s->add_quad({4.5f, 0.0f, -1.5f}, {0, 0, 3}, {0, 3, 0}, s->add_material(emitter(vec3(30.0f))));  // faces -x
  s->add_sphere({-0.5f, 0.6f, -1.0f}, 0.6f, s->add_material(diffuse({0.7f, 0.3f, 0.2f})));
  s->add_box({0.5f, 0.0f, 0.8f}, {1.3f, 0.9f, 1.6f}, s->add_material(coated({0.3f, 0.5f, 0.7f}, 0.2f)));
  return s;
}

std::unique_ptr<Scene> fireflies() {
  auto s = std::make_unique<Scene>();
  Material floor = coated({0.3f, 0.3f, 0.32f}, 0.05f);
  floor.albedo_map = Pattern::Tiles;
  floor.albedo2 = {0.05f, 0.05f, 0.05f};
  const int fl = s->add_material(floor);
  const int wall = s->add_material(diffuse(vec3(0.25f)));
  add_room(*s, {-3, 0, -3}, {3, 3, 3}, fl, wall, wall, wall, wall, wall);
  s->add_sphere({0.0f, 2.2f, 0.0f}, 0.04f, s->add_material(emitter(vec3(1500.0f))));
  s->add_sphere({-1.0f, 0.5f, 0.0f}, 0.5f, s->add_material(metal({0.9f, 0.9f, 0.92f}, 0.08f)));
  s->add_sphere({1.0f, 0.5f, 0.3f}, 0.5f, s->add_material(metal({0.95f, 0.64f, 0.54f}, 0.2f)));
  s->add_box({-0.4f, 0.0f, -1.6f}, {0.4f, 0.7f, -0.8f}, s->add_material(coated({0.6f, 0.1f, 0.1f}, 0.03f)));
  s->add_point_light({2.0f, 2.5f, 2.0f}, vec3(1.5f));
  return s;
}

// BRDF-map detail (paper 000): a coated floor and a metal back panel whose
// roughness alternates between 0.03 and 0.4 in 1/6 m checks and stripes,
// with a large area light near the panel that both reflect, so a filter that
// blurs the specular signal visibly loses the pattern.
std::unique_ptr<Scene> roughness_map() {
  auto s = std::make_unique<Scene>();
  Material floor = coated({0.12f, 0.12f, 0.13f}, 0.03f);  // dark, so its coat reflections show
  floor.roughness_map = Pattern::Checker;
  floor.alpha2 = 0.4f;
  floor.map_scale = 6.0f;
  const int fl = s->add_material(floor);
  Material panel = metal({0.95f, 0.8f, 0.6f}, 0.03f);
  panel.roughness_map = Pattern::Stripes;
  panel.alpha2 = 0.4f;
  panel.map_scale = 6.0f;
  const int back = s->add_material(panel);
  const int wall = s->add_material(diffuse(vec3(0.5f)));
  add_room(*s, {-4, 0, -4}, {4, 4, 4}, fl, wall, wall, wall, back, wall);
  s->add_quad({-2.0f, 3.98f, -3.9f}, {4, 0, 0}, {0, 0, 2}, s->add_material(emitter(vec3(8.0f))));
  s->add_sphere({0.0f, 0.7f, -1.5f}, 0.7f, s->add_material(diffuse({0.6f, 0.3f, 0.2f})));
  return s;
}

// Reflection motion (paper 001): a large planar mirror on the back wall and a
// glossy floor (alpha 0.18, no maps: glossy class everywhere), under a small
// ceiling light. The camera translates sideways, so what the mirror and the
// floor reflect moves differently from the surfaces themselves. The wall
// behind the camera is checkered, so the mirror image has texture to match.
std::unique_ptr<Scene> mirror_floor() {
  auto s = std::make_unique<Scene>();
  const int fl = s->add_material(coated({0.35f, 0.3f, 0.25f}, 0.18f));
  const int white = s->add_material(diffuse(vec3(0.7f)));
  const int red = s->add_material(diffuse({0.6f, 0.12f, 0.1f}));
  const int blue = s->add_material(diffuse({0.15f, 0.25f, 0.6f}));
  Material checks = diffuse({0.75f, 0.75f, 0.7f});
  checks.albedo_map = Pattern::Checker;
  checks.albedo2 = {0.15f, 0.35f, 0.2f};
  const int front = s->add_material(checks);
  add_room(*s, {-4, 0, -4}, {4, 3, 4}, fl, white, red, blue, white, front);
  // The mirror, 2 cm in front of the back wall, facing +z.
  s->add_quad({-3.0f, 0.15f, -3.98f}, {6, 0, 0}, {0, 2.55f, 0}, s->add_material(metal(vec3(0.95f), 0.0f)));
  s->add_quad({-0.5f, 2.98f, 0.0f}, {1, 0, 0}, {0, 0, 1}, s->add_material(emitter(vec3(30.0f))));
  s->add_box({-1.9f, 0.0f, -1.6f}, {-0.9f, 1.0f, -0.6f}, s->add_material(diffuse({0.75f, 0.45f, 0.2f})));
  s->add_box({1.5f, 0.0f, -0.5f}, {2.1f, 1.6f, 0.1f}, white);
  s->add_sphere({0.5f, 0.5f, -2.0f}, 0.5f, s->add_material(diffuse({0.2f, 0.5f, 0.3f})));
  s->add_sphere({-0.5f, 0.35f, 0.6f}, 0.35f, s->add_material(diffuse({0.8f, 0.7f, 0.2f})));
  return s;
}

struct Pose {
  vec3 eye, target;
  float fov_degrees;
};

// 0, 1, ..., n, n-1, ..., 0, 1, ...: dollies go back and forth, so long sequences stay in the scene.
float back_and_forth(int frame, int n) {
  const int p = ((frame % (2 * n)) + 2 * n) % (2 * n);
  return static_cast<float>(p <= n ? p : 2 * n - p);
}

Pose pose(int scene_id, int frame) {
  const float f = static_cast<float>(frame);
  switch (scene_id) {
    case 1: {
      const float a = -0.35f + 0.015f * f;
      return {{3.3f * std::sin(a), 1.7f, 3.3f * std::cos(a)}, {0.0f, 0.9f, -0.5f}, 55.0f};
    }
    case 2: {
      const vec3 eye(-8.0f + 0.12f * back_and_forth(frame, 130), 1.6f, 4.0f);
      return {eye, eye + vec3(0.25f, -0.15f, -1.0f), 60.0f};
    }
    case 3:
      return {{-2.3f, 1.4f, 2.2f}, {2.0f, 0.7f, -0.5f + 1.5f * std::sin(0.04f * f)}, 60.0f};
    case 4:
      return {{-2.5f + 0.03f * back_and_forth(frame, 150), 1.5f, 2.6f}, {0.0f, 0.6f, 0.0f}, 55.0f};
    case 5:
      return {{-1.0f + 0.02f * back_and_forth(frame, 100), 1.2f, 3.0f}, {0.0f, 1.0f, -4.0f}, 60.0f};
    case 6: {
      // Translation only (the view direction is fixed): 0.02 m/frame sideways, turning back every 120 frames.
      const vec3 eye(-1.2f + 0.02f * back_and_forth(frame, 120), 1.4f, 2.4f);
      return {eye, eye + vec3(0.0f, -0.15f, -1.0f), 55.0f};
    }
  }
  throw std::invalid_argument("scene id must be 1.." + std::to_string(kSceneCount));
}

}  // namespace

std::unique_ptr<Scene> build_scene(int scene_id) {
  std::unique_ptr<Scene> s;
  switch (scene_id) {
    case 1: s = room(); break;
    case 2: s = pillars(); break;
    case 3: s = gap(); break;
    case 4: s = fireflies(); break;
    case 5: s = roughness_map(); break;
    case 6: s = mirror_floor(); break;
    default: throw std::invalid_argument("scene id must be 1.." + std::to_string(kSceneCount));
  }
  s->commit();
  return s;
}

std::string scene_name(int scene_id) {
  static const char* names[] = {"room", "pillars", "gap", "fireflies", "roughness", "mirror-floor"};
  if (scene_id < 1 || scene_id > kSceneCount) throw std::invalid_argument("unknown scene");
  return names[scene_id - 1];
}

Camera scene_camera(int scene_id, int frame, int width, int height) {
  const Pose p = pose(scene_id, frame);
  Camera c;
  c.view = glm::lookAt(p.eye, p.target, vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(p.fov_degrees), static_cast<float>(width) / static_cast<float>(height),
                                  0.05f, 200.0f);
  return c;
}

}  // namespace dn::render
