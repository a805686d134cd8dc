#include "scene.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "sampling.hpp"

namespace dn::render {
namespace {

void embree_error(void*, RTCError code, const char* message) {
  throw std::runtime_error("embree error " + std::to_string(static_cast<int>(code)) + ": " + (message ? message : ""));
}

// 1 - cos(theta_max) of the cone a sphere of radius r subtends at distance^2 d2,
// without the cancellation of 1 - sqrt(1 - x) for small, far lights.
float cone_one_minus_cos(float r, float d2) {
  const float sin2 = r * r / d2;
  return sin2 / (1.0f + std::sqrt(std::max(0.0f, 1.0f - sin2)));
}

// Analytic ray-sphere tests for Embree's user geometry (one sphere per geometry).
void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const glm::vec4& s = *static_cast<const glm::vec4*>(args->geometryUserPtr);
  *args->bounds_o = RTCBounds{s.x - s.w, s.y - s.w, s.z - s.w, 0.0f, s.x + s.w, s.y + s.w, s.z + s.w, 0.0f};
}

// The nearest root of |o + t d - c| = r in (tnear, tfar), or a negative value.
float sphere_root(const glm::vec4& s, const glm::vec3& o, const glm::vec3& d, float tnear, float tfar) {
  const glm::vec3 oc = o - glm::vec3(s);
  const float a = glm::dot(d, d);
  const float b = glm::dot(oc, d);
  const float c = glm::dot(oc, oc) - s.w * s.w;
  const float disc = b * b - a * c;
  if (disc < 0.0f) return -1.0f;
  const float root = std::sqrt(disc);
  float t = (-b - root) / a;
  if (t <= tnear) t = (-b + root) / a;
  return (t > tnear && t < tfar) ? t : -1.0f;
}

void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  const glm::vec4& s = *static_cast<const glm::vec4*>(args->geometryUserPtr);
  RTCRayHitN* rayhit = args->rayhit;
  RTCRayN* ray = RTCRayHitN_RayN(rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (!args->valid[i]) continue;
    const glm::vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i), RTCRayN_org_z(ray, args->N, i));
    const glm::vec3 d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i), RTCRayN_dir_z(ray, args->N, i));
    const float t = sphere_root(s, o, d, RTCRayN_tnear(ray, args->N, i), RTCRayN_tfar(ray, args->N, i));
    if (t < 0.0f) continue;
    const glm::vec3 n = o + t * d - glm::vec3(s);
    RTCRayN_tfar(ray, args->N, i) = t;
    RTCHitN_Ng_x(hit, args->N, i) = n.x;
    RTCHitN_Ng_y(hit, args->N, i) = n.y;
    RTCHitN_Ng_z(hit, args->N, i) = n.z;
    RTCHitN_u(hit, args->N, i) = 0.0f;
    RTCHitN_v(hit, args->N, i) = 0.0f;
    RTCHitN_primID(hit, args->N, i) = args->primID;
    RTCHitN_geomID(hit, args->N, i) = args->geomID;
    RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
  }
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  const glm::vec4& s = *static_cast<const glm::vec4*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (!args->valid[i]) continue;
    RTCRayN* ray = args->ray;
    const glm::vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i), RTCRayN_org_z(ray, args->N, i));
    const glm::vec3 d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i), RTCRayN_dir_z(ray, args->N, i));
    if (sphere_root(s, o, d, RTCRayN_tnear(ray, args->N, i), RTCRayN_tfar(ray, args->N, i)) >= 0.0f)
      RTCRayN_tfar(ray, args->N, i) = -INFINITY;
  }
}

}  // namespace

glm::vec3 offset_origin(const glm::vec3& p, const glm::vec3& normal, const glm::vec3& dir) {
  const float scale = 1e-4f * (1.0f + std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}));
  return p + (glm::dot(normal, dir) >= 0.0f ? scale : -scale) * normal;
}

Scene::Scene(glm::vec3 environment) : environment_(environment) {
  device_ = rtcNewDevice("verbose=0");
  if (!device_) throw std::runtime_error("embree: cannot create a device");
  rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
  scene_ = rtcNewScene(device_);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_NONE);
}

Scene::~Scene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

int Scene::add_material(const Material& m) {
  materials_.push_back(m);
  return static_cast<int>(materials_.size() - 1);
}

void Scene::add_triangles(const std::vector<glm::vec3>& vertices, const std::vector<glm::uvec3>& triangles,
                          int material, int light) {
  RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i)
    for (int c = 0; c < 3; ++c) v[3 * i + c] = vertices[i][c];
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), triangles.size()));
  Shape shape;
  shape.material = material;
  shape.light = light;
  for (size_t i = 0; i < triangles.size(); ++i) {
    for (int c = 0; c < 3; ++c) idx[3 * i + c] = triangles[i][c];
    const glm::vec3 &a = vertices[triangles[i].x], &b = vertices[triangles[i].y], &c = vertices[triangles[i].z];
    shape.normals.push_back(glm::normalize(glm::cross(b - a, c - a)));
  }
  rtcCommitGeometry(geom);
  const unsigned id = rtcAttachGeometry(scene_, geom);
  rtcReleaseGeometry(geom);
  if (id != shapes_.size()) throw std::logic_error("embree geometry ids are expected to be dense");
  shapes_.push_back(std::move(shape));
}

void Scene::add_quad(const glm::vec3& corner, const glm::vec3& u, const glm::vec3& v, int material) {
  int light = -1;
  if (materials_[material].kind == MaterialKind::Emitter) {
    Light l;
    l.kind = Light::Kind::Quad;
    l.position = corner;
    l.edge_u = u;
    l.edge_v = v;
    const glm::vec3 c = glm::cross(u, v);
    l.area = glm::length(c);
    l.normal = c / l.area;
    l.radiance = materials_[material].emission;
    light = static_cast<int>(lights_.size());
    lights_.push_back(l);
  }
  add_triangles({corner, corner + u, corner + u + v, corner + v}, {{0, 1, 2}, {0, 2, 3}}, material, light);
}

void Scene::add_box(const glm::vec3& lo, const glm::vec3& hi, int material) {
  std::vector<glm::vec3> v;
  for (int i = 0; i < 8; ++i) v.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  // Counter-clockwise seen from outside, so normals point out.
  const std::vector<glm::uvec3> t = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5},   // -x, +x
                                     {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},   // -y, +y
                                     {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};  // -z, +z
  add_triangles(v, t, material, -1);
}

void Scene::add_sphere(const glm::vec3& centre, float radius, int material) {
  spheres_.emplace_back(centre, radius);
  RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geom, 1);
  rtcSetGeometryUserData(geom, &spheres_.back());
  rtcSetGeometryBoundsFunction(geom, sphere_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geom, sphere_intersect);
  rtcSetGeometryOccludedFunction(geom, sphere_occluded);
  rtcCommitGeometry(geom);
  const unsigned id = rtcAttachGeometry(scene_, geom);
  rtcReleaseGeometry(geom);
  if (id != shapes_.size()) throw std::logic_error("embree geometry ids are expected to be dense");
  Shape shape;
  shape.material = material;
  shape.sphere = true;
  shape.centre = centre;
  shape.radius = radius;
  if (materials_[material].kind == MaterialKind::Emitter) {
    Light l;
    l.kind = Light::Kind::Sphere;
    l.position = centre;
    l.radius = radius;
    l.area = 4.0f * kPi * radius * radius;
    l.radiance = materials_[material].emission;
    shape.light = static_cast<int>(lights_.size());
    lights_.push_back(l);
  }
  shapes_.push_back(std::move(shape));
}

void Scene::add_point_light(const glm::vec3& position, const glm::vec3& intensity) {
  Light l;
  l.kind = Light::Kind::Point;
  l.position = position;
  l.radiance = intensity;
  lights_.push_back(l);
}

void Scene::commit() {
  rtcCommitScene(scene_);
  // Lights are chosen in proportion to their emitted power.
  float total = 0.0f;
  std::vector<float> power;
  for (const Light& l : lights_) {
    const float p = l.kind == Light::Kind::Point ? 4.0f * kPi * luminance(l.radiance)
                                                 : kPi * l.area * luminance(l.radiance);
    power.push_back(std::max(p, 1e-9f));
    total += power.back();
  }
  light_cdf_.clear();
  float running = 0.0f;
  for (size_t i = 0; i < lights_.size(); ++i) {
    lights_[i].select_probability = power[i] / total;
    running += power[i] / total;
    light_cdf_.push_back(running);
  }
  if (!light_cdf_.empty()) light_cdf_.back() = 1.0f;
}

Hit Scene::intersect_surface(const Hit& on, const glm::vec3& o, const glm::vec3& d) const {
  Hit hit;
  const Shape& s = shapes_[on.geometry];
  if (s.sphere) {
    hit.t = sphere_root(glm::vec4(s.centre, s.radius), o, d, 0.0f, INFINITY);
    if (!(hit.t > 0.0f)) return hit;
    hit.position = o + hit.t * d;
    hit.normal = glm::normalize(hit.position - s.centre);
  } else {
    const float denom = glm::dot(d, on.normal);
    if (denom == 0.0f) return hit;
    hit.t = glm::dot(on.position - o, on.normal) / denom;
    if (!(hit.t > 0.0f)) return hit;
    hit.position = o + hit.t * d;
    hit.normal = on.normal;
  }
  hit.found = true;
  hit.geometry = on.geometry;
  return hit;
}

Hit Scene::intersect(const glm::vec3& o, const glm::vec3& d, TraceContext& ctx, float tfar) const {
  RTCRayHit rh;
  rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
  rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = tfar;
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &ctx.embree, &rh);
  ++ctx.rays;
  Hit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.found = true;
  hit.t = rh.ray.tfar;
  hit.position = o + hit.t * d;
  hit.geometry = rh.hit.geomID;
  const Shape& s = shapes_[hit.geometry];
  if (s.sphere) {
    hit.normal = glm::normalize(hit.position - s.centre);
  } else {
    hit.normal = s.normals[rh.hit.primID];
  }
  return hit;
}

bool Scene::occluded(const glm::vec3& o, const glm::vec3& d, float tfar, TraceContext& ctx) const {
  RTCRay ray;
  ray.org_x = o.x, ray.org_y = o.y, ray.org_z = o.z;
  ray.dir_x = d.x, ray.dir_y = d.y, ray.dir_z = d.z;
  ray.tnear = 0.0f;
  ray.tfar = tfar;
  ray.time = 0.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(scene_, &ctx.embree, &ray);
  ++ctx.rays;
  return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

glm::vec3 Scene::emitted(const Hit& hit, const glm::vec3& dir) const {
  const Material& m = material_of(hit);
  if (m.kind != MaterialKind::Emitter) return glm::vec3(0.0f);
  if (!shapes_[hit.geometry].sphere && glm::dot(hit.normal, dir) >= 0.0f) return glm::vec3(0.0f);
  return m.emission;
}

LightSample Scene::sample_light(const glm::vec3& p, float u_select, glm::vec2 u) const {
  LightSample s;
  if (lights_.empty()) return s;
  const size_t index =
      std::min(static_cast<size_t>(std::lower_bound(light_cdf_.begin(), light_cdf_.end(), u_select) - light_cdf_.begin()),
               lights_.size() - 1);
  const Light& l = lights_[index];
  switch (l.kind) {
    case Light::Kind::Point: {
      const glm::vec3 d = l.position - p;
      const float d2 = glm::dot(d, d);
      if (d2 <= 0.0f) return s;
      s.distance = std::sqrt(d2);
      s.wi = d / s.distance;
      s.radiance = l.radiance / (d2 * l.select_probability);  // the choice is folded into the value
      s.delta = true;
      break;
    }
    case Light::Kind::Quad: {
      const glm::vec3 y = l.position + u.x * l.edge_u + u.y * l.edge_v;
      const glm::vec3 d = y - p;
      const float d2 = glm::dot(d, d);
      s.distance = std::sqrt(d2);
      s.wi = d / s.distance;
      const float cos_l = -glm::dot(s.wi, l.normal);
      if (cos_l <= 0.0f) return s;
      s.radiance = l.radiance;
      s.pdf = l.select_probability * d2 / (cos_l * l.area);
      break;
    }
    case Light::Kind::Sphere: {
      const glm::vec3 dc = l.position - p;
      const float d2 = glm::dot(dc, dc);
      if (d2 <= l.radius * l.radius) return s;
      const float one_minus = cone_one_minus_cos(l.radius, d2);
      const glm::vec3 local = sample_cone(u, 1.0f - one_minus);
      s.wi = glm::normalize(Frame(dc / std::sqrt(d2)).to_world(local));
      const float b = glm::dot(s.wi, dc);
      const float disc = l.radius * l.radius - (d2 - b * b);
      s.distance = b - std::sqrt(std::max(0.0f, disc));
      s.radiance = l.radiance;
      s.pdf = l.select_probability / (2.0f * kPi * one_minus);
      break;
    }
  }
  s.valid = true;
  return s;
}

float Scene::light_pdf(int light, const glm::vec3& from, const Hit& hit) const {
  const Light& l = lights_[light];
  switch (l.kind) {
    case Light::Kind::Point:
      return 0.0f;
    case Light::Kind::Quad: {
      const glm::vec3 d = hit.position - from;
      const float d2 = glm::dot(d, d);
      const float cos_l = std::fabs(glm::dot(d, l.normal)) / std::sqrt(d2);
      return cos_l > 0.0f ? l.select_probability * d2 / (cos_l * l.area) : 0.0f;
    }
    case Light::Kind::Sphere: {
      const glm::vec3 dc = l.position - from;
      const float d2 = glm::dot(dc, dc);
      if (d2 <= l.radius * l.radius) return 0.0f;
      return l.select_probability / (2.0f * kPi * cone_one_minus_cos(l.radius, d2));
    }
  }
  return 0.0f;
}

}  // namespace dn::render
