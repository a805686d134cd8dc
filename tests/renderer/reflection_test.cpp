// The reflection features (protocol channels 15-21, docs/protocol.md §7.5)
// against what a mirror does analytically: planar mirrors unfolded, a chain
// through two mirrors traced independently here with its Fresnel factors,
// footprints against finite differences of neighbouring pixels' hits, and
// the classes (which pixels get which features) on the built-in scenes.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "scenes.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

using test::at3;

constexpr int kW = 64, kH = 36;

Camera look_at(glm::vec3 eye, glm::vec3 target, float fov_degrees) {
  Camera c;
  c.view = glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(fov_degrees), float(kW) / kH, 0.05f, 500.0f);
  return c;
}

Material metal(glm::vec3 f0) {
  Material m;
  m.kind = MaterialKind::Metal;
  m.albedo = f0;
  m.alpha = 0.0f;  // clamped to kMinAlpha: mirror class, a pure mirror
  return m;
}

Material lambert(glm::vec3 albedo) {
  Material m;
  m.albedo = albedo;
  return m;
}

FrameBuffers render_reflection(const Scene& scene, const Camera& camera) {
  RenderSettings st = test::small_settings(kW, kH);
  st.channels.split = false;
  st.channels.reflection = true;
  return render_frame(scene, camera, camera, 0, st);
}

// The camera ray of sample 0 (no jitter: the pixel centre).
glm::vec3 camera_ray(const Camera& camera, int x, int y) {
  return CameraRays(camera, kW, kH).direction(x + 0.5f, y + 0.5f);
}

// A planar mirror z = 0 (facing +z, F0 0.9) and a grey Lambert wall at
// z = 8 behind an oblique camera: every mirror ray comes back to the wall.
struct PlanarMirror {
  static constexpr float kWall = 8.0f;
  Scene scene;
  Camera camera = look_at({1.5f, 1.0f, 5.0f}, {0.0f, 0.0f, 0.0f}, 45.0f);
  PlanarMirror() {
    scene.add_quad({-10, -10, 0}, {20, 0, 0}, {0, 20, 0}, scene.add_material(metal(glm::vec3(0.9f))));
    scene.add_quad({-40, -40, kWall}, {0, 80, 0}, {80, 0, 0}, scene.add_material(lambert(glm::vec3(0.5f))));
    scene.commit();
  }
};

// (a) The chain's hit is where the camera ray, continued through the mirror,
// meets the wall mirrored to z = -8 (then mirrored back); the virtual depth
// is the view depth scaled by that unfolded length over the primary's.
TEST(RendererReflection, PlanarMirrorMatchesTheUnfoldedCameraRay) {
  const PlanarMirror m;
  const FrameBuffers fb = render_reflection(m.scene, m.camera);
  const glm::vec3 eye = glm::vec3(glm::inverse(m.camera.view)[3]);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      ASSERT_LT(fb.roughness[i], kMirrorRoughness) << "pixel " << i;
      const glm::vec3 d = camera_ray(m.camera, x, y);
      const float t1 = -eye.z / d.z;                         // to the mirror
      const float t = (-PlanarMirror::kWall - eye.z) / d.z;  // to the mirrored wall
      const glm::vec3 unfolded = eye + t * d;
      const glm::vec3 expected(unfolded.x, unfolded.y, -unfolded.z);
      EXPECT_LE(glm::distance(at3(fb.reflection_position, i), expected), 1e-3f * t) << "pixel " << i;
      EXPECT_NEAR(fb.reflection_depth[i], fb.depth[i] * t / t1, 1e-3f * fb.reflection_depth[i]) << "pixel " << i;
      const glm::vec3 r = at3(fb.reflection_direction, i);
      EXPECT_NEAR(glm::length(r), 1.0f, 1e-5f);
      EXPECT_LE(glm::distance(r, glm::vec3(d.x, d.y, -d.z)), 1e-5f) << "pixel " << i;  // reflect(d, +z)
      EXPECT_NEAR(fb.reflection_distance[i], t - t1, 1e-3f * t) << "pixel " << i;
      EXPECT_LE(glm::distance(at3(fb.reflection_normal, i), glm::vec3(0, 0, -1)), 1e-6f);  // facing the chain
      EXPECT_LE(glm::distance(at3(fb.reflection_albedo, i), glm::vec3(0.5f)), 1e-6f);  // no mirror after the primary
    }
}

// (d) On a planar mirror the footprint is the spacing of neighbouring
// pixels' hits: central differences of reflection_position.
TEST(RendererReflection, FootprintMatchesNeighbourSpacingOnAPlanarMirror) {
  const PlanarMirror m;
  const FrameBuffers fb = render_reflection(m.scene, m.camera);
  double worst = 0.0;
  for (int y = 1; y < kH - 1; ++y)
    for (int x = 1; x < kW - 1; ++x) {
      const size_t i = size_t(y) * kW + x;
      const float dx = 0.5f * glm::distance(at3(fb.reflection_position, i + 1), at3(fb.reflection_position, i - 1));
      const float dy = 0.5f * glm::distance(at3(fb.reflection_position, i + kW), at3(fb.reflection_position, i - kW));
      const float fd = 0.5f * (dx + dy);
      worst = std::max(worst, double(std::fabs(fb.reflection_footprint[i] - fd) / fd));
    }
  EXPECT_LT(worst, 0.02) << "worst relative difference";
}

// The same on a convex mirror, where the reflected rays spread faster than
// the camera's (the normal turns with the position, dN = dP / r): a sphere of
// radius 2 seen from 8 m, reflecting a wall behind the camera. Only pixels
// that see the sphere nearly head-on, so that their neighbours do too.
TEST(RendererReflection, FootprintMatchesNeighbourSpacingOnAMirrorSphere) {
  Scene scene;
  scene.add_sphere({0, 0, 0}, 2.0f, scene.add_material(metal(glm::vec3(0.9f))));
  scene.add_quad({-100, -100, 12}, {0, 200, 0}, {200, 0, 0}, scene.add_material(lambert(glm::vec3(0.5f))));
  scene.commit();
  const Camera camera = look_at({0, 0, 8}, {0, 0, 0}, 30.0f);
  const FrameBuffers fb = render_reflection(scene, camera);
  double worst = 0.0;
  int checked = 0;
  for (int y = 1; y < kH - 1; ++y)
    for (int x = 1; x < kW - 1; ++x) {
      const size_t i = size_t(y) * kW + x;
      bool head_on = true;
      for (size_t j : {i, i - 1, i + 1, i - kW, i + kW})
        head_on = head_on && !std::isinf(fb.depth[j]) &&
                  glm::dot(at3(fb.normal, j), -camera_ray(camera, int(j % kW), int(j / kW))) > 0.9f;
      if (!head_on) continue;
      ++checked;
      const float dx = 0.5f * glm::distance(at3(fb.reflection_position, i + 1), at3(fb.reflection_position, i - 1));
      const float dy = 0.5f * glm::distance(at3(fb.reflection_position, i + kW), at3(fb.reflection_position, i - kW));
      const float fd = 0.5f * (dx + dy);
      worst = std::max(worst, double(std::fabs(fb.reflection_footprint[i] - fd) / fd));
    }
  EXPECT_GT(checked, 100);
  EXPECT_LT(worst, 0.03) << "worst relative difference over " << checked << " pixels";
}

// A corner of three perpendicular planes: mirror floor A (y = 0, grey F0
// 0.9), mirror wall B (x = 2, coloured F0), Lambert wall C (z = -10). From
// this camera about 230 of the pixels see a chain A -> B -> C at grazing
// angles on B (cos 0.07-0.5), where Schlick's Fresnel is far from F0.
struct Corner {
  struct Rect {
    int axis;
    glm::vec3 lo, hi;  // lo[axis] == hi[axis]: the plane
    Material material;
  };
  std::vector<Rect> rects = {
      {1, {-50, 0, -10}, {2, 0, 50}, metal(glm::vec3(0.9f))},
      {0, {2, 0, -10}, {2, 50, 50}, metal({0.9f, 0.5f, 0.2f})},
      {2, {-50, 0, -10}, {2, 50, -10}, lambert({0.5f, 0.6f, 0.7f})},
  };
  Scene scene;
  Camera camera = look_at({0.5f, 1.5f, 6.0f}, {1.5f, 0.0f, -2.0f}, 50.0f);
  Corner() {
    for (const Rect& r : rects) {
      const glm::vec3 size = r.hi - r.lo;
      const int a = (r.axis + 1) % 3, b = (r.axis + 2) % 3;
      glm::vec3 u(0.0f), v(0.0f);
      u[a] = size[a];
      v[b] = size[b];
      scene.add_quad(r.lo, u, v, scene.add_material(r.material));
    }
    scene.commit();
  }

  struct Chain {
    glm::vec3 position{0.0f}, normal{0.0f}, albedo{1.0f};
    float primary_t = 0.0f, length = 0.0f;
    int mirrors_after_primary = 0;
    bool primary_is_mirror = false;
    bool near_edge = false;  // some hit within 1 cm of a rectangle's edge: Embree may pick the neighbour
  };

  // The nearest rectangle along a ray, by plane intersection.
  std::optional<std::pair<int, float>> nearest(glm::vec3 o, glm::vec3 d) const {
    std::optional<std::pair<int, float>> best;
    for (int k = 0; k < int(rects.size()); ++k) {
      const Rect& r = rects[size_t(k)];
      if (std::fabs(d[r.axis]) < 1e-9f) continue;
      const float t = (r.lo[r.axis] - o[r.axis]) / d[r.axis];
      if (t <= 1e-4f || (best && t >= best->second)) continue;
      const glm::vec3 p = o + t * d;
      bool inside = true;
      for (int c = 0; c < 3; ++c)
        if (c != r.axis) inside = inside && p[c] >= r.lo[c] - 1e-3f && p[c] <= r.hi[c] + 1e-3f;
      if (inside) best = {k, t};
    }
    return best;
  }

  // The mirror chain of the camera ray d, traced here: reflect off the mirrors
  // (F0 grey or coloured), stop at the Lambert wall; the reflectance of every
  // mirror after the primary from Schlick's formula at the incidence cosine.
  std::optional<Chain> trace(glm::vec3 o, glm::vec3 d) const {
    Chain c;
    for (int segment = 0; segment < 8; ++segment) {
      const auto hit = nearest(o, d);
      if (!hit) return std::nullopt;
      const Rect& r = rects[size_t(hit->first)];
      const glm::vec3 p = o + hit->second * d;
      for (int a = 0; a < 3; ++a)
        if (a != r.axis) c.near_edge |= std::min(std::fabs(p[a] - r.lo[a]), std::fabs(p[a] - r.hi[a])) < 0.01f;
      if (segment == 0) c.primary_t = hit->second;
      else c.length += hit->second;
      glm::vec3 n(0.0f);
      n[r.axis] = d[r.axis] > 0.0f ? -1.0f : 1.0f;  // facing the ray
      if (segment == 0) c.primary_is_mirror = r.material.kind == MaterialKind::Metal;
      if (r.material.kind != MaterialKind::Metal) {
        c.position = p, c.normal = n, c.albedo *= r.material.albedo;
        return c;
      }
      if (segment > 0) {
        const float cos_i = std::fabs(d[r.axis]);
        const glm::vec3 f0 = r.material.albedo;
        c.albedo *= f0 + (glm::vec3(1.0f) - f0) * std::pow(1.0f - cos_i, 5.0f);
        ++c.mirrors_after_primary;
      }
      d[r.axis] = -d[r.axis];
      o = p;
    }
    return std::nullopt;
  }
};

// (c) Through two mirrors: the albedo is the Lambert wall's times the second
// mirror's Fresnel reflectance at the chain's incidence angle (the primary's
// own reflectance is not in it), and position, normal and virtual depth match.
TEST(RendererReflection, ChainThroughTwoMirrorsCarriesTheSecondMirrorsFresnel) {
  const Corner corner;
  const FrameBuffers fb = render_reflection(corner.scene, corner.camera);
  const glm::vec3 eye = glm::vec3(glm::inverse(corner.camera.view)[3]);
  int two_mirror = 0, checked = 0;
  float max_fresnel_effect = 0.0f;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (reflection_class(fb.roughness[i]) != ReflectionClass::Mirror) continue;
      const auto chain = corner.trace(eye, camera_ray(corner.camera, x, y));
      ASSERT_TRUE(chain) << "pixel " << i;
      // A pixel mostly on a mirror but whose centre ray hits the Lambert wall
      // is mirror class too; its chain starts on the wall, which trace() does not do.
      if (chain->near_edge || !chain->primary_is_mirror) continue;
      ++checked;
      EXPECT_LE(glm::distance(at3(fb.reflection_position, i), chain->position),
                1e-3f * (chain->primary_t + chain->length))
          << "pixel " << i;
      EXPECT_LE(glm::distance(at3(fb.reflection_normal, i), chain->normal), 1e-6f) << "pixel " << i;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(fb.reflection_albedo[3 * i + c], chain->albedo[c], 1e-4f) << "pixel " << i;
      EXPECT_NEAR(fb.reflection_depth[i], fb.depth[i] * (chain->primary_t + chain->length) / chain->primary_t,
                  1e-3f * fb.reflection_depth[i])
          << "pixel " << i;
      if (chain->mirrors_after_primary == 1) {
        ++two_mirror;
        // How far the reflectance is from F0 alone: the test would notice F0 in place of Fresnel.
        const float f0_only_blue = corner.rects[2].material.albedo.b * corner.rects[1].material.albedo.b;
        max_fresnel_effect = std::max(max_fresnel_effect, std::fabs(chain->albedo.b - f0_only_blue));
      }
    }
  EXPECT_GT(checked, kW * kH / 2);
  EXPECT_GT(two_mirror, 200);
  EXPECT_GT(max_fresnel_effect, 0.05f);
}

// (b) Which pixels get what, by the roughness the frame sends: rough and
// diffuse pixels and the background nothing, glossy ones the representative
// ray (direction, distance, footprint) but no chain, mirror ones all seven.
// The extra rays are the representative rays plus the further chain
// segments, and nothing else.
TEST(RendererReflection, ClassesGetTheirFeaturesAndOnlyThemTraceRays) {
  for (int scene_id : {1, 6}) {
    const std::unique_ptr<Scene> scene = build_scene(scene_id);
    RenderSettings st = test::small_settings(kW, kH);
    const Camera cam = frame_camera(scene_id, 3, st), prev = frame_camera(scene_id, 2, st);
    const FrameBuffers without = render_frame(*scene, cam, prev, 3, st);
    EXPECT_TRUE(without.reflection_direction.empty() && without.reflection_footprint.empty());
    st.channels.reflection = true;
    const FrameBuffers fb = render_frame(*scene, cam, prev, 3, st);
    int count[3] = {0, 0, 0};
    for (int i = 0; i < kW * kH; ++i) {
      const glm::vec3 dir = at3(fb.reflection_direction, i);
      const bool chain = glm::length(at3(fb.reflection_position, i)) > 0.0f ||
                         glm::length(at3(fb.reflection_albedo, i)) > 0.0f ||
                         glm::length(at3(fb.reflection_normal, i)) > 0.0f || fb.reflection_depth[i] != 0.0f;
      const bool ray =
          glm::length(dir) > 0.0f || fb.reflection_distance[i] != 0.0f || fb.reflection_footprint[i] != 0.0f;
      const ReflectionClass cls = std::isinf(fb.depth[i]) ? ReflectionClass::None : reflection_class(fb.roughness[i]);
      ++count[int(cls)];
      if (cls == ReflectionClass::None) {
        ASSERT_FALSE(chain || ray) << "scene " << scene_id << " pixel " << i;
        continue;
      }
      // The rooms are closed: every representative ray and chain ends on a surface.
      ASSERT_NEAR(glm::length(dir), 1.0f, 1e-5f) << "scene " << scene_id << " pixel " << i;
      ASSERT_GT(fb.reflection_distance[i], 0.0f) << "scene " << scene_id << " pixel " << i;
      ASSERT_GT(fb.reflection_footprint[i], 0.0f) << "scene " << scene_id << " pixel " << i;
      if (cls == ReflectionClass::Glossy) {
        ASSERT_FALSE(chain) << "scene " << scene_id << " pixel " << i;
        continue;
      }
      ASSERT_NEAR(glm::length(at3(fb.reflection_normal, i)), 1.0f, 1e-5f) << "scene " << scene_id << " pixel " << i;
      ASSERT_GT(fb.reflection_depth[i], fb.depth[i]) << "scene " << scene_id << " pixel " << i;
      // The chain's first segment is the representative ray: its length is at least that ray's distance.
      const float t1 = glm::distance(at3(fb.position, i), glm::vec3(glm::inverse(cam.view)[3]));
      ASSERT_GE(fb.reflection_depth[i], fb.depth[i] * (t1 + fb.reflection_distance[i]) / t1 * (1.0f - 1e-4f))
          << "scene " << scene_id << " pixel " << i;
    }
    const int none = count[int(ReflectionClass::None)], glossy = count[int(ReflectionClass::Glossy)],
              mirror = count[int(ReflectionClass::Mirror)];
    EXPECT_GT(none, 50) << "scene " << scene_id;
    EXPECT_GT(glossy, 50) << "scene " << scene_id;
    EXPECT_GT(mirror, 50) << "scene " << scene_id;
    // The radiance samples are the same (the features use no random numbers):
    // the difference is the reflection rays, one per glossy pixel, 1 to
    // kMirrorChainLength (8) per mirror pixel.
    const uint64_t extra = fb.rays - without.rays;
    EXPECT_GE(extra, uint64_t(glossy + mirror)) << "scene " << scene_id;
    EXPECT_LE(extra, uint64_t(glossy + 8 * mirror)) << "scene " << scene_id;
    EXPECT_EQ(fb.radiance, without.radiance) << "scene " << scene_id;
  }
}

}  // namespace
}  // namespace dn::render
