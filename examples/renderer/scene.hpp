// A scene: Embree 3 geometry (triangles for quads and boxes, analytic user
// geometry for spheres: 10.0 against 7.4 Mrays/s per thread for Embree's
// sphere points in a small benchmark here), materials, lights and a constant
// environment. Built once, then read-only and shared by the render threads.
#pragma once

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <deque>
#include <vector>

#include "material.hpp"

namespace dn::render {

struct Light {
  enum class Kind { Quad, Sphere, Point };
  Kind kind = Kind::Quad;
  glm::vec3 position{0.0f};  // quad corner, sphere centre or point position
  glm::vec3 edge_u{0.0f}, edge_v{0.0f}, normal{0.0f};  // quad: emits towards normal = cross(u, v)
  float area = 0.0f;
  float radius = 0.0f;         // sphere
  glm::vec3 radiance{0.0f};    // area lights: emitted radiance; point lights: intensity (W/sr)
  float select_probability = 0.0f;  // by power, set by Scene::commit
};

struct LightSample {
  glm::vec3 wi{0.0f};
  float distance = 0.0f;     // to the sampled point, for the shadow ray
  glm::vec3 radiance{0.0f};  // arriving radiance (point lights: I / d^2)
  float pdf = 0.0f;          // solid angle, light choice included; 0 for point lights (delta)
  bool delta = false;
  bool valid = false;
};

struct Hit {
  bool found = false;
  float t = 0.0f;
  glm::vec3 position{0.0f};
  glm::vec3 normal{0.0f};  // geometric, unit, as modelled (not flipped towards the ray)
  uint32_t geometry = 0;
};

// Per-thread tracing state: Embree's context and the ray count for Mrays/s.
struct TraceContext {
  RTCIntersectContext embree;
  uint64_t rays = 0;
  TraceContext() { rtcInitIntersectContext(&embree); }
};

class Scene {
 public:
  explicit Scene(glm::vec3 environment = glm::vec3(0.0f));
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  int add_material(const Material& m);
  // A parallelogram; an Emitter material makes it a one-sided area light facing cross(u, v).
  void add_quad(const glm::vec3& corner, const glm::vec3& u, const glm::vec3& v, int material);
  void add_box(const glm::vec3& lo, const glm::vec3& hi, int material);
  void add_sphere(const glm::vec3& centre, float radius, int material);
  void add_point_light(const glm::vec3& position, const glm::vec3& intensity);
  void commit();  // builds the BVH and the light-selection table

  Hit intersect(const glm::vec3& origin, const glm::vec3& dir, TraceContext& ctx, float tfar = INFINITY) const;
  bool occluded(const glm::vec3& origin, const glm::vec3& dir, float tfar, TraceContext& ctx) const;

  // The intersection of a ray with the surface `on` lies on, without Embree and
  // without occlusion: a sphere's sphere, a triangle's (unbounded) plane. For
  // G-buffer sub-samples of a pixel whose footprint is known to lie on `on`.
  Hit intersect_surface(const Hit& on, const glm::vec3& origin, const glm::vec3& dir) const;
  bool is_sphere(const Hit& hit) const { return shapes_[hit.geometry].sphere; }
  // How fast the surface's normal turns with position: 1/radius on a sphere, 0 on a plane.
  float curvature(const Hit& hit) const {
    const Shape& s = shapes_[hit.geometry];
    return s.sphere ? 1.0f / s.radius : 0.0f;
  }

  const Material& material_of(const Hit& hit) const { return materials_[shapes_[hit.geometry].material]; }
  // Emitted radiance leaving the hit towards -dir (one-sided quads emit only on their front).
  glm::vec3 emitted(const Hit& hit, const glm::vec3& dir) const;
  int light_of(const Hit& hit) const { return shapes_[hit.geometry].light; }

  bool has_lights() const { return !lights_.empty(); }
  const std::vector<Light>& lights() const { return lights_; }
  LightSample sample_light(const glm::vec3& p, float u_select, glm::vec2 u) const;
  // Solid-angle pdf (light choice included) with which sample_light, called at
  // `from`, would have picked the point `hit` on light `light`.
  float light_pdf(int light, const glm::vec3& from, const Hit& hit) const;

  const glm::vec3& environment() const { return environment_; }

 private:
  struct Shape {
    int material = 0;
    int light = -1;
    bool sphere = false;
    glm::vec3 centre{0.0f};
    float radius = 0.0f;  // sphere
    std::vector<glm::vec3> normals;  // per triangle
  };
  void add_triangles(const std::vector<glm::vec3>& vertices, const std::vector<glm::uvec3>& triangles, int material,
                     int light);

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  glm::vec3 environment_;
  std::vector<Material> materials_;
  std::vector<Shape> shapes_;  // indexed by Embree geometry id
  std::deque<glm::vec4> spheres_;  // centre, radius: Embree's user data, so never moved
  std::vector<Light> lights_;
  std::vector<float> light_cdf_;
};

// Pushes a ray origin off the surface so the next ray does not hit it again.
glm::vec3 offset_origin(const glm::vec3& p, const glm::vec3& normal, const glm::vec3& dir);

}  // namespace dn::render
