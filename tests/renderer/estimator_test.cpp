// Next-event estimation with MIS and plain BSDF sampling are two unbiased
// estimators of the same image: their means agree, for the whole radiance and
// for each lobe of the split. A wrong light pdf or MIS weight shows up here.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

#include "scenes.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

struct Means {
  glm::dvec3 radiance{0.0}, diffuse{0.0}, specular{0.0};
};

Means image_means(const Scene& scene, const Camera& cam, bool next_event, double spp) {
  RenderSettings st = test::small_settings(32, 18, spp);
  st.next_event = next_event;
  st.max_depth = 3;
  const FrameBuffers fb = render_frame(scene, cam, cam, 0, st);
  Means m;
  const double n = double(st.width) * st.height;
  for (size_t i = 0; i < size_t(n); ++i) {
    m.radiance += glm::dvec3(test::at3(fb.radiance, i)) / n;
    m.diffuse += glm::dvec3(test::at3(fb.diffuse, i)) / n;
    m.specular += glm::dvec3(test::at3(fb.specular, i)) / n;
  }
  return m;
}

void expect_same(const Means& a, const Means& b, const char* what) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(a.radiance[c], b.radiance[c], 0.03 * b.radiance[c]) << what << " radiance channel " << c;
    EXPECT_NEAR(a.diffuse[c], b.diffuse[c], 0.04 * b.diffuse[c]) << what << " diffuse channel " << c;
    EXPECT_NEAR(a.specular[c], b.specular[c], 0.06 * b.specular[c] + 1e-4) << what << " specular channel " << c;
  }
}

TEST(RendererEstimators, QuadLightNextEventMatchesBsdfSampling) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  const Camera cam = scene_camera(1, 0, 32, 18);
  expect_same(image_means(*scene, cam, true, 512), image_means(*scene, cam, false, 512), "room");
}

TEST(RendererEstimators, SphereLightNextEventMatchesBsdfSampling) {
  Scene scene;
  Material floor;
  floor.kind = MaterialKind::Coated;
  floor.albedo = glm::vec3(0.6f, 0.5f, 0.4f);
  floor.alpha = 0.15f;
  Material gold;
  gold.kind = MaterialKind::Metal;
  gold.albedo = glm::vec3(1.0f, 0.8f, 0.4f);
  gold.alpha = 0.3f;
  Material light;
  light.kind = MaterialKind::Emitter;
  light.emission = glm::vec3(40.0f);
  scene.add_box({-3, -1, -3}, {3, 0, 3}, scene.add_material(floor));
  scene.add_sphere({0.5f, 0.6f, 0.0f}, 0.6f, scene.add_material(gold));
  scene.add_sphere({-0.8f, 1.6f, 0.3f}, 0.3f, scene.add_material(light));
  scene.commit();
  Camera cam;
  cam.view = glm::lookAt(glm::vec3(0, 1.5f, 3.5f), glm::vec3(0, 0.4f, 0), glm::vec3(0, 1, 0));
  cam.projection = glm::perspective(glm::radians(55.0f), 32.0f / 18.0f, 0.1f, 100.0f);
  // The small light seen through glossy lobes makes BSDF sampling noisy: more samples.
  expect_same(image_means(scene, cam, true, 2048), image_means(scene, cam, false, 2048), "sphere light");
}

// A Lambertian floor under a point light: every sample is exactly
// albedo / pi * I cos(theta) / d^2 (one light, nothing to bounce towards).
TEST(RendererEstimators, PointLightMatchesTheClosedForm) {
  Scene scene;
  Material floor;
  floor.albedo = glm::vec3(0.5f);
  scene.add_quad({-5, 0, -5}, {0, 0, 10}, {10, 0, 0}, scene.add_material(floor));
  const glm::vec3 light(0.3f, 2.0f, -0.2f), intensity(3.0f, 2.0f, 1.0f);
  scene.add_point_light(light, intensity);
  scene.commit();
  Camera cam;
  cam.view = glm::lookAt(glm::vec3(0, 3, 0), glm::vec3(0), glm::vec3(0, 0, -1));
  cam.projection = glm::perspective(glm::radians(60.0f), 32.0f / 18.0f, 0.1f, 100.0f);
  const FrameBuffers fb = render_frame(scene, cam, cam, 0, test::small_settings(32, 18, 1.0));
  for (size_t i = 0; i < 32 * 18; ++i) {
    const glm::vec3 p = test::at3(fb.position, i);
    const glm::vec3 to_light = light - p;
    const float d2 = glm::dot(to_light, to_light);
    const glm::vec3 expected = 0.5f / 3.14159265f * intensity * (to_light.y / std::sqrt(d2)) / d2;
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(fb.radiance[3 * i + c], expected[c], 1e-4f * expected[c]) << i;
  }
}

}  // namespace
}  // namespace dn::render
