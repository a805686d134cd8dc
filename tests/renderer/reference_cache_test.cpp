// References are rendered once and then reused from the cache.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "dn/image/exr_io.hpp"
#include "reference_cache.hpp"
#include "scenes.hpp"

namespace dn::render {
namespace {

TEST(RendererReferenceCache, SecondRequestReusesTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("dn_renderer_cache_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::unique_ptr<Scene> scene = build_scene(2);
  ReferenceRequest rq;
  rq.scene_id = 2;
  rq.width = 32;
  rq.height = 18;
  rq.frame = 4;
  rq.spp = 4;
  rq.cache_dir = dir.string();
  bool rendered = false;
  const std::string path = ensure_reference(*scene, rq, rendered);
  EXPECT_TRUE(rendered);
  EXPECT_EQ(path, reference_path(dir.string(), 2, 32, 18, 4, 4));
  EXPECT_NE(path.find("pillars_32x18_spp4_v" + std::to_string(kReferenceVersion) + "/ref_0004.exr"), std::string::npos)
      << path;
  const auto mtime = std::filesystem::last_write_time(path);

  const std::string again = ensure_reference(*scene, rq, rendered);
  EXPECT_FALSE(rendered);
  EXPECT_EQ(again, path);
  EXPECT_EQ(std::filesystem::last_write_time(path), mtime);

  int w = 0, h = 0;
  const std::vector<float> rgb = image::read_exr_rgb(path, w, h);
  EXPECT_EQ(w, 32);
  EXPECT_EQ(h, 18);
  // Another spp is another file.
  rq.spp = 2;
  ensure_reference(*scene, rq, rendered);
  EXPECT_TRUE(rendered);
  std::filesystem::remove_all(dir);
}

// The second reference: its own cache key, its own seed, and the same image in
// expectation (the mean of r1 - r2 is zero within its standard error).
TEST(RendererReferenceCache, SecondReferenceIsIndependent) {
  const auto dir = std::filesystem::temp_directory_path() / ("dn_renderer_cache2_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::unique_ptr<Scene> scene = build_scene(1);
  ReferenceRequest rq;
  rq.scene_id = 1;
  rq.width = 64;
  rq.height = 36;
  rq.frame = 3;
  rq.spp = 16;
  rq.cache_dir = dir.string();
  bool rendered = false;
  const std::string p1 = ensure_reference(*scene, rq, rendered);
  rq.index = 2;
  const std::string p2 = ensure_reference(*scene, rq, rendered);
  EXPECT_TRUE(rendered);
  EXPECT_NE(p1, p2);
  EXPECT_EQ(p2, reference_path(dir.string(), 1, 64, 36, 3, 16, 2));
  EXPECT_NE(p2.find("/ref2_0003.exr"), std::string::npos) << p2;
  EXPECT_NE(reference_seed(rq.seed, 2), reference_seed(rq.seed, 1));
  ensure_reference(*scene, rq, rendered);  // cached like the first
  EXPECT_FALSE(rendered);

  int w = 0, h = 0;
  const std::vector<float> r1 = image::read_exr_rgb(p1, w, h), r2 = image::read_exr_rgb(p2, w, h);
  ASSERT_EQ(r1.size(), r2.size());
  double sum = 0.0, sum2 = 0.0;
  size_t differing = 0;
  for (size_t i = 0; i < r1.size(); ++i) {
    const double d = double(r1[i]) - r2[i];
    sum += d;
    sum2 += d * d;
    differing += d != 0.0;
  }
  const double n = double(r1.size()), mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  // Independent noise: nearly every lit pixel differs (the light itself and the background are exact).
  EXPECT_GT(differing, r1.size() * 3 / 4);
  // Same expectation: the mean difference is within 4 standard errors of zero.
  EXPECT_LT(std::fabs(mean), 4.0 * sd / std::sqrt(n)) << "mean " << mean << " sd " << sd;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dn::render
