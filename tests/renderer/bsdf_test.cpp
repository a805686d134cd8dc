// White-furnace style checks of the BSDF sampling and of the integrator.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

#include "bsdf.hpp"
#include "sampling.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

glm::vec3 direction_at(float cos_theta) {
  return {std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta)), 0.0f, cos_theta};
}

TEST(RendererBsdf, LambertAlbedoOneReflectsEverything) {
  SurfaceParams s;
  s.diffuse_albedo = glm::vec3(1.0f);
  s.has_diffuse = true;
  Rng rng(1, 0, 0);
  for (float cos_o : {0.05f, 0.5f, 1.0f}) {
    const Bsdf bsdf(s, direction_at(cos_o));
    double sum = 0;
    const int n = 20000;
    for (int k = 0; k < n; ++k) {
      const BsdfSample b = bsdf.sample(rng.next(), rng.next2());
      ASSERT_TRUE(b.valid);
      sum += b.weight.x;
      // eval and sample agree: f cos / pdf is the weight.
      const BsdfEval e = bsdf.eval(b.wi);
      ASSERT_NEAR(e.f_diffuse.x * b.wi.z / e.pdf_diffuse, b.weight.x, 1e-4);
    }
    EXPECT_NEAR(sum / n, 1.0, 1e-6);
  }
}

TEST(RendererBsdf, GgxWeightsAreFiniteAndAtMostOneForWhiteMetal) {
  Rng rng(2, 0, 0);
  for (float alpha : {0.001f, 0.05f, 0.2f, 0.5f, 1.0f}) {
    for (float cos_o : {0.02f, 0.3f, 0.7f, 1.0f}) {
      SurfaceParams s;
      s.f0 = glm::vec3(1.0f);
      s.alpha = alpha;
      s.has_specular = true;
      const Bsdf bsdf(s, direction_at(cos_o));
      double sum = 0;
      const int n = 20000;
      for (int k = 0; k < n; ++k) {
        const BsdfSample b = bsdf.sample(rng.next(), rng.next2());
        if (!b.valid) continue;  // a reflection below the horizon carries nothing
        ASSERT_TRUE(std::isfinite(b.weight.x) && std::isfinite(b.pdf)) << alpha << " " << cos_o;
        ASSERT_LE(b.weight.x, 1.0f + 1e-4f) << alpha << " " << cos_o;
        sum += b.weight.x;
        if (alpha >= 0.05f && b.wi.z > 1e-3f) {
          const BsdfEval e = bsdf.eval(b.wi);
          ASSERT_NEAR(e.f_specular.x * b.wi.z / e.pdf_specular, b.weight.x, 2e-3f * (1.0f + b.weight.x));
          ASSERT_NEAR(e.pdf_specular, b.pdf, 1e-3f * b.pdf);
        }
      }
      const double albedo = sum / n;
      // Single-scattering GGX loses energy at high roughness, never gains it.
      EXPECT_LE(albedo, 1.0 + 1e-3) << alpha << " " << cos_o;
      if (alpha <= 0.05f && cos_o >= 0.3f) {
        EXPECT_GT(albedo, 0.98) << alpha << " " << cos_o;
      }
    }
  }
}

TEST(RendererBsdf, CoatedLobesSampleWhatTheyEvaluate) {
  SurfaceParams s;
  s.diffuse_albedo = glm::vec3(0.5f, 0.6f, 0.7f);
  s.f0 = glm::vec3(kDielectricF0);
  s.alpha = 0.3f;
  s.has_diffuse = s.has_specular = true;
  const Bsdf bsdf(s, direction_at(0.6f));
  Rng rng(3, 0, 0);
  for (int k = 0; k < 5000; ++k) {
    const BsdfSample b = bsdf.sample(rng.next(), rng.next2());
    if (!b.valid) continue;
    const BsdfEval e = bsdf.eval(b.wi);
    const glm::vec3 f = b.lobe == Lobe::Diffuse ? e.f_diffuse : e.f_specular;
    const float pdf = b.lobe == Lobe::Diffuse ? e.pdf_diffuse : e.pdf_specular;
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(f[c] * b.wi.z / pdf, b.weight[c], 2e-3f * (1.0f + b.weight[c]));
  }
}

// A white Lambertian sphere under a uniform white sky: every path leaves the
// convex sphere after one bounce, so every sample is exactly 1.
TEST(RendererBsdf, WhiteFurnaceSphereIsOne) {
  Scene scene(glm::vec3(1.0f));
  Material white;
  white.kind = MaterialKind::Diffuse;
  white.albedo = glm::vec3(1.0f);
  scene.add_sphere({0.0f, 0.0f, 0.0f}, 1.0f, scene.add_material(white));
  scene.commit();
  RenderSettings st = test::small_settings(64, 36, 4.0);
  Camera cam;
  cam.view = glm::lookAt(glm::vec3(0, 0, 3), glm::vec3(0), glm::vec3(0, 1, 0));
  cam.projection = glm::perspective(glm::radians(60.0f), 64.0f / 36.0f, 0.1f, 100.0f);
  const FrameBuffers fb = render_frame(scene, cam, cam, 0, st);
  int hits = 0;
  for (int i = 0; i < st.width * st.height; ++i) {
    if (!std::isinf(fb.depth[i])) ++hits;
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(fb.radiance[3 * i + c], 1.0f, 1e-4f) << "pixel " << i;
  }
  EXPECT_GT(hits, 64 * 36 / 8);
}

}  // namespace
}  // namespace dn::render
