// The material G-buffers are pixel-footprint averages: on a textured plane
// under light that is known exactly, albedo x lighting matches a supersampled
// reference of the radiance in every pixel. Point-sampled albedo does not.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "test_support.hpp"

namespace dn::render {
namespace {

constexpr int kW = 128, kH = 72;
constexpr float kEnvironment = 1.5f;

// A Lambert checker plane under a constant environment and nothing else: a
// path's radiance is exactly albedo(primary hit) x kEnvironment (the bounce
// ray escapes; there are no lights for NEE), so the pixel's true radiance is
// kEnvironment x the footprint average of the albedo.
struct CheckerPlane {
  Scene scene{glm::vec3(kEnvironment)};
  Camera camera;
  CheckerPlane() {
    Material m;
    m.albedo = glm::vec3(0.5f, 0.45f, 0.4f);
    m.albedo2 = glm::vec3(0.4f, 0.45f, 0.5f);
    m.albedo_map = Pattern::Checker;
    m.map_scale = 7.0f;  // cells of 1/7 m: 2 to 5 pixels across here, so nearly every pixel sees an edge nearby
    scene.add_quad({-20, 0, -20}, {0, 0, 40}, {40, 0, 0}, scene.add_material(m));
    scene.commit();
    // Looking down at 50 degrees, rotated so the checker edges are oblique in the image.
    camera.view = glm::lookAt(glm::vec3(0.3f, 2.0f, 1.7f), glm::vec3(-0.4f, 0.0f, -0.2f), glm::vec3(0, 1, 0));
    camera.projection = glm::perspective(glm::radians(40.0f), float(kW) / kH, 0.1f, 100.0f);
  }
};

// The radiance averaged over an S x S grid of pixel-centre samples per pixel:
// a (S W) x (S H) 1-spp render (its one sample is the pixel centre), box-downsampled.
std::vector<double> supersampled_radiance(const CheckerPlane& p, int s) {
  RenderSettings st = test::small_settings(kW * s, kH * s, 1.0);
  st.channels = ChannelSet{false, false, false, false, false, false, false};
  const FrameBuffers fb = render_frame(p.scene, p.camera, p.camera, 0, st);
  std::vector<double> ref(size_t(kW) * kH * 3, 0.0);
  for (int y = 0; y < kH * s; ++y)
    for (int x = 0; x < kW * s; ++x)
      for (int c = 0; c < 3; ++c)
        ref[(size_t(y / s) * kW + x / s) * 3 + c] += fb.radiance[(size_t(y) * kW * s + x) * 3 + c] / (s * s);
  return ref;
}

// The largest relative error of albedo x E (1 spp, G-buffer grid `grid`) against the reference.
double worst_remodulation_error(const CheckerPlane& p, const std::vector<double>& ref, int grid) {
  RenderSettings st = test::small_settings(kW, kH, 1.0);
  st.gbuffer_grid = grid;
  const FrameBuffers fb = render_frame(p.scene, p.camera, p.camera, 0, st);
  double worst = 0.0;
  for (size_t i = 0; i < size_t(kW) * kH * 3; ++i) {
    worst = std::max(worst, std::fabs(fb.albedo[i] * kEnvironment - ref[i]) / ref[i]);
  }
  return worst;
}

TEST(RendererGbuffer, FootprintAlbedoRemodulatesToTheReference) {
  const CheckerPlane plane;
  const std::vector<double> ref = supersampled_radiance(plane, 32);
  const double averaged = worst_remodulation_error(plane, ref, 4);  // the default grid
  const double point = worst_remodulation_error(plane, ref, 0);     // the old point-sampled G-buffer
  const double one = worst_remodulation_error(plane, ref, 1);       // 1x1 rays, 4x4 leaves on a face
  std::printf("worst relative error of albedo x E: 4x4 %.4f, point %.4f, 1x1 %.4f\n", averaged, point, one);
  EXPECT_LE(averaged, 0.02);
  EXPECT_GT(point, 0.02);
  EXPECT_GT(one, 0.02);
}

}  // namespace
}  // namespace dn::render
