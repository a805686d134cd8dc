// The G-buffers follow the protocol's conventions (docs/protocol.md §7):
// motion p_prev = p + mv in pixels (checked by re-tracing the previous frame's
// camera through p + mv, not by the formula that made mv), unit world
// normals, depth = view-space z of the position, and the split identity.
#include <gtest/gtest.h>

#include <cmath>

#include "scenes.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

using test::at3;

struct Reprojection {
  int checked = 0, matched = 0;
};

// For every non-silhouette pixel whose p + sign*mv lands inside the image,
// whether the previous camera sees the same world point there.
Reprojection reproject(int scene_id, bool jitter, float sign) {
  const std::unique_ptr<Scene> scene = build_scene(scene_id);
  RenderSettings st = test::small_settings();
  st.jitter = jitter;
  st.channels.split = false;
  const int frame = 5;
  const Camera cam = frame_camera(scene_id, frame, st), prev = frame_camera(scene_id, frame - 1, st);
  const FrameBuffers fb = render_frame(*scene, cam, prev, frame, st);
  const glm::vec3 eye = glm::vec3(glm::inverse(cam.view)[3]);
  Reprojection r;
  for (int y = 1; y < st.height - 1; ++y)
    for (int x = 1; x < st.width - 1; ++x) {
      const size_t i = size_t(y) * st.width + x;
      const float d = fb.depth[i];
      if (std::isinf(d)) continue;
      // Silhouettes: a neighbour more than 5 % nearer or farther.
      bool silhouette = false;
      for (size_t j : {i - 1, i + 1, i - st.width, i + st.width})
        silhouette |= !(std::fabs(fb.depth[j] - d) <= 0.05f * d);
      if (silhouette) continue;
      // The sample position is the pixel centre plus the frame's jitter.
      const glm::vec2 p(x + 0.5f + cam.jitter.x, y + 0.5f + cam.jitter.y);
      const glm::vec2 q = p + sign * glm::vec2(fb.motion[2 * i], fb.motion[2 * i + 1]);
      if (q.x < 0 || q.y < 0 || q.x >= st.width || q.y >= st.height) continue;
      // Previous frame's camera without jitter: motion is defined between unjittered projections.
      Camera prev_unjittered = prev;
      prev_unjittered.jitter = glm::vec2(0.0f);
      glm::vec3 seen;
      ++r.checked;
      if (!primary_position(*scene, prev_unjittered, st.width, st.height, q.x, q.y, seen)) continue;
      const glm::vec3 world = at3(fb.position, i);
      if (glm::length(seen - world) <= 1e-3f * glm::length(world - eye)) ++r.matched;
    }
  return r;
}

TEST(RendererConventions, MotionVectorsReprojectStaticSceneExactly) {
  for (int scene_id = 1; scene_id <= kSceneCount; ++scene_id) {
    const Reprojection r = reproject(scene_id, false, 1.0f);
    ASSERT_GT(r.checked, 128 * 72 / 2) << "scene " << scene_id;
    // Rays that graze a triangle edge may land on the neighbouring triangle of the same surface: allow a few.
    EXPECT_GE(r.matched, r.checked * 995 / 1000) << "scene " << scene_id << ": " << r.matched << "/" << r.checked;
  }
}

TEST(RendererConventions, MotionVectorsHoldWithJitter) {
  const Reprojection r = reproject(2, true, 1.0f);
  EXPECT_GE(r.matched, r.checked * 995 / 1000) << r.matched << "/" << r.checked;
}

TEST(RendererConventions, NegatedMotionConventionFails) {
  for (int scene_id : {1, 2}) {
    const Reprojection r = reproject(scene_id, false, -1.0f);
    EXPECT_LT(r.matched, r.checked / 2) << "scene " << scene_id << ": " << r.matched << "/" << r.checked;
  }
}

TEST(RendererConventions, NormalsUnitDepthIsViewZ) {
  for (int scene_id = 1; scene_id <= kSceneCount; ++scene_id) {
    const std::unique_ptr<Scene> scene = build_scene(scene_id);
    const RenderSettings st = test::small_settings(64, 36);
    const Camera cam = frame_camera(scene_id, 2, st);
    const FrameBuffers fb = render_frame(*scene, cam, frame_camera(scene_id, 1, st), 2, st);
    int hits = 0;
    for (int i = 0; i < st.width * st.height; ++i) {
      const float d = fb.depth[i];
      if (std::isinf(d)) {
        EXPECT_GT(d, 0.0f);
        continue;
      }
      ++hits;
      ASSERT_GT(d, 0.0f);
      ASSERT_NEAR(glm::length(at3(fb.normal, i)), 1.0f, 1e-5f) << "scene " << scene_id << " pixel " << i;
      const float view_z = -(cam.view * glm::vec4(at3(fb.position, i), 1.0f)).z;
      ASSERT_NEAR(d, view_z, 1e-5f * d) << "scene " << scene_id << " pixel " << i;
    }
    EXPECT_GT(hits, st.width * st.height / 2) << "scene " << scene_id;
  }
}

TEST(RendererConventions, RadianceIsDiffusePlusSpecularPlusEmission) {
  for (int scene_id = 1; scene_id <= kSceneCount; ++scene_id) {
    const std::unique_ptr<Scene> scene = build_scene(scene_id);
    const RenderSettings st = test::small_settings(64, 36, 2.0);
    const Camera cam = frame_camera(scene_id, 0, st);
    const FrameBuffers fb = render_frame(*scene, cam, cam, 0, st);
    double diffuse = 0, specular = 0;
    for (int i = 0; i < st.width * st.height; ++i) {
      const glm::vec3 sum = at3(fb.diffuse, i) + at3(fb.specular, i) + at3(fb.emission, i);
      const glm::vec3 rad = at3(fb.radiance, i);
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(rad[c], sum[c], 1e-4f * (1.0f + rad[c])) << "pixel " << i;
      diffuse += fb.diffuse[3 * i];
      specular += fb.specular[3 * i];
    }
    // Both lobes carry light in every scene.
    EXPECT_GT(diffuse, 0.0) << "scene " << scene_id;
    EXPECT_GT(specular, 0.0) << "scene " << scene_id;
  }
}

// The reflection features follow the radiance sample 0 ray, jitter included,
// as depth and position do: the representative ray starts at `position`,
// leaves along the primary normal's mirror direction, and its hit at
// `reflection_distance` is where the chain goes next.
TEST(RendererConventions, ReflectionFeaturesFollowTheSampleZeroRay) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  RenderSettings st = test::small_settings(64, 36);
  st.channels.reflection = true;
  st.jitter = true;
  // Point-sampled material G-buffers follow the same ray (footprint averages
  // mix the mirror's normal with its neighbours' at its edge).
  st.gbuffer_grid = 0;
  const Camera cam = frame_camera(1, 3, st);
  const FrameBuffers fb = render_frame(*scene, cam, frame_camera(1, 2, st), 3, st);
  const CameraRays rays(cam, st.width, st.height);
  int mirror = 0, glossy = 0;
  for (int y = 0; y < st.height; ++y)
    for (int x = 0; x < st.width; ++x) {
      const size_t i = size_t(y) * st.width + x;
      const glm::vec3 r = at3(fb.reflection_direction, i);
      if (glm::length(r) == 0.0f) continue;
      ASSERT_LT(fb.roughness[i], kGlossyRoughness);
      const glm::vec3 d = rays.direction(x + 0.5f + cam.jitter.x, y + 0.5f + cam.jitter.y);
      const glm::vec3 n = at3(fb.normal, i);
      ASSERT_LE(glm::distance(r, glm::reflect(d, n)), 1e-5f) << "pixel " << i;
      if (fb.roughness[i] >= kMirrorRoughness) {
        ++glossy;
        continue;
      }
      ++mirror;
      // A chain that stops at its first hit ends at the representative ray's
      // hit (up to the ray's offset off the surface, 1e-4 of the coordinates).
      const glm::vec3 first = at3(fb.position, i) + fb.reflection_distance[i] * r;
      if (glm::distance(first, at3(fb.reflection_position, i)) <= 1e-3f * (1.0f + fb.reflection_distance[i])) continue;
      // Otherwise it went on from a pure mirror, and the room's only one is the mirror sphere.
      ASSERT_NEAR(glm::distance(first, glm::vec3(-1.5f, 1.0f, -1.2f)), 1.0f, 1e-3f) << "pixel " << i;
    }
  EXPECT_GT(mirror, 20);  // the mirror sphere and the coated floor's mirror stripes
  EXPECT_GT(glossy, 20);  // the gold sphere and the floor's rough stripes
}

}  // namespace
}  // namespace dn::render
