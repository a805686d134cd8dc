// The F_beta table (server/pipelines/stages/fb_lut.hpp, server/pipelines/stages/fb_lut.comp) against
// the independent double-precision CPU reference (fb_lut_reference.cpp), its
// properties, the bilinear lookup of fb_lut.glsl (through the fb_lut_probe
// kernel) and the per-context cache (gpu::Context::shared).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <regex>
#include <thread>
#include <vector>

#include "dn/shaders/shaders.hpp"
#include "fb_lut_reference.hpp"
#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu_test_env.hpp"
#include "text_file.hpp"
#include "pipelines/stages/fb_lut.hpp"
#include "pipelines/pass.hpp"

namespace dn {
namespace {

using pipelines::kFbLutSize;

constexpr uint32_t N = kFbLutSize;

double axis(uint32_t i) { return (i + 0.5) / N; }

struct Table {
  std::vector<float> v;  // A, B interleaved
  float a(uint32_t i, uint32_t j) const { return v[2 * (size_t{j} * N + i)]; }
  float b(uint32_t i, uint32_t j) const { return v[2 * (size_t{j} * N + i) + 1]; }
};

// Every 8th row/column plus the last, and every texel of the first and last
// rows and columns (the α → 0, α → 1, cos θ_o → 0 and cos θ_o → 1 edges).
std::vector<std::pair<uint32_t, uint32_t>> reference_texels(bool with_edges) {
  std::vector<uint32_t> lines;
  for (uint32_t i = 0; i < N; i += 8) lines.push_back(i);
  lines.push_back(N - 1);
  std::vector<std::pair<uint32_t, uint32_t>> texels;
  for (uint32_t j : lines)
    for (uint32_t i : lines) texels.push_back({i, j});
  if (with_edges) {
    for (uint32_t k = 0; k < N; ++k) {
      if (k % 8 == 0 || k == N - 1) continue;  // already in the grid
      for (uint32_t e : {0u, N - 1}) {
        texels.push_back({k, e});
        texels.push_back({e, k});
      }
    }
  }
  return texels;
}

// Runs f(index) for index in [0, count) on the machine's cores.
template <class F>
void parallel_for(size_t count, const F& f) {
  const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  std::atomic<size_t> next{0};
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      for (size_t k = next++; k < count; k = next++) f(k);
    });
  for (auto& t : pool) t.join();
}

class FbLutTest : public test::GpuTest {
 protected:
  // The context's table, read back once per test binary.
  const Table& table() {
    static const Table t{pipelines::fb_lut(ctx()).read()};
    return t;
  }

  // dn_fb_lut(cos, α) on the device for each point (fb_lut_probe.comp).
  std::vector<float> probe(const std::vector<float>& points) {
    const uint32_t count = static_cast<uint32_t>(points.size() / 2);
    // The declaration's bindings (the table is a texel binding), constant 0 the workgroup size.
    auto kernel = ctx().kernels().get(pipelines::kernel_desc(*shaders::declaration("fb_lut_probe"), {{0, 64}}));

    gpu::Buffer uniform(ctx(), 16, gpu::BufferKind::Constants, "probe:constants");
    const uint32_t constants[4] = {count, 0, 0, 0};
    uniform.write({reinterpret_cast<const uint8_t*>(constants), sizeof constants});
    const uint64_t bytes = uint64_t{count} * 8;
    gpu::Buffer in(ctx(), bytes, gpu::BufferKind::StorageUpload, "probe:points");
    in.write({reinterpret_cast<const uint8_t*>(points.data()), bytes});
    gpu::Buffer out(ctx(), bytes, gpu::BufferKind::StorageDownload, "probe:results");

    gpu::DescriptorPool pool(ctx(), 1, 3);
    const VkBuffer storage[] = {in.handle(), pipelines::fb_lut(ctx()).buffer().handle(), out.handle()};
    VkDescriptorSet set = pool.allocate(*kernel, uniform.handle(), storage);

    gpu::CommandStream stream(ctx());
    VkCommandBuffer cmd = stream.begin();
    in.record_upload(cmd, bytes);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel->pipeline());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, kernel->layout(), 0, 1, &set, 0, nullptr);
    vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
    out.record_readback(cmd, bytes, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    stream.submit_and_wait();
    std::vector<float> results(size_t{count} * 2);
    out.read({reinterpret_cast<uint8_t*>(results.data()), bytes});
    return results;
  }
};

// fb_lut.glsl's DN_FB_LUT_SIZE is the same number as kFbLutSize (the one
// GLSL and the one C++ definition of the table size).
TEST(FbLutDefinition, GlslSizeMatchesCpp) {
  const std::string s = test::read_text(DN_FB_LUT_GLSL);
  std::smatch m;
  const std::regex define(R"(#define\s+DN_FB_LUT_SIZE\s+(\d+)\s)");
  ASSERT_TRUE(std::regex_search(s, m, define)) << "no #define DN_FB_LUT_SIZE in " << DN_FB_LUT_GLSL;
  EXPECT_EQ(std::stoul(m[1].str()), kFbLutSize);
  // Exactly one definition.
  EXPECT_EQ(std::distance(std::sregex_iterator(s.begin(), s.end(), define), std::sregex_iterator()), 1);
}

// The reference's two quadratures (light-space and half-vector-space) agree
// where both apply, including grazing cos θ_o: each checks the other.
TEST(FbLutReference, QuadraturesAgree) {
  double worst = 0;
  for (double alpha : {0.02, 0.05, 0.1, 0.3, 0.7, 1.0})
    for (double c : {0.5 / N, 0.01, 0.1, 0.5, 0.9, 1.0}) {
      const auto l = test::fb_reference(c, alpha, test::FbQuadrature::LightSpace);
      const auto h = test::fb_reference(c, alpha, test::FbQuadrature::HalfVectorSpace);
      worst = std::max({worst, std::abs(l.a - h.a), std::abs(l.b - h.b)});
      EXPECT_NEAR(l.a, h.a, 2e-5) << "alpha " << alpha << ", cos " << c;
      EXPECT_NEAR(l.b, h.b, 2e-5) << "alpha " << alpha << ", cos " << c;
    }
  std::printf("reference: light-space vs half-vector quadrature, max |difference| %.2e\n", worst);
}

// Sanity of the reference itself: at α → 0 GGX is a mirror, F_beta → F(cos θ_o),
// i.e. A → 1 − (1 − cos)^5 and B → (1 − cos)^5 (G2 → 1 away from grazing).
TEST(FbLutReference, MirrorLimit) {
  for (double c : {0.2, 0.5, 0.9, 1.0}) {
    const auto r = test::fb_reference(c, 1e-3);
    const double s = std::pow(1 - c, 5);
    EXPECT_NEAR(r.a, 1 - s, 1e-4) << c;
    EXPECT_NEAR(r.b, s, 1e-4) << c;
  }
}

// (g) One table per context: fb_lut(ctx) always returns the same object.
TEST_F(FbLutTest, ComputedOncePerContext) {
  const pipelines::FbLut& first = pipelines::fb_lut(ctx());
  const pipelines::FbLut& second = pipelines::fb_lut(ctx());
  EXPECT_EQ(&first, &second);
  EXPECT_EQ(first.buffer().handle(), second.buffer().handle());
  EXPECT_EQ(first.buffer().size(), uint64_t{N} * N * 8);
  std::vector<const pipelines::FbLut*> seen(8);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < seen.size(); ++t) threads.emplace_back([&, t] { seen[t] = &pipelines::fb_lut(ctx()); });
  for (auto& t : threads) t.join();
  for (const auto* p : seen) EXPECT_EQ(p, &first);
  std::printf("F_beta LUT: %ux%u, %u samples, computed in %.1f ms on %s\n", N, N, pipelines::kFbLutSamples,
              first.compute_ms(), ctx().name().c_str());
}

// Context::shared: concurrent first callers get one object, built once; a
// throwing factory stores nothing.
TEST_F(FbLutTest, ContextSharedBuildsOncePerType) {
  struct Probe {
    int id;
  };
  std::atomic<int> built{0};
  std::vector<Probe*> seen(6);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < seen.size(); ++t)
    threads.emplace_back([&, t] {
      seen[t] = &ctx().shared<Probe>([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        return std::make_unique<Probe>(Probe{++built});
      });
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(built.load(), 1);
  for (auto* p : seen) EXPECT_EQ(p, seen[0]);

  struct Failing {};
  EXPECT_THROW(ctx().shared<Failing>([]() -> std::unique_ptr<Failing> { throw std::runtime_error("no"); }),
               std::runtime_error);
  Failing& ok = ctx().shared<Failing>([] { return std::make_unique<Failing>(); });
  EXPECT_EQ(&ok, &ctx().shared<Failing>([]() -> std::unique_ptr<Failing> { throw std::runtime_error("again"); }));
}

// (a) Every reference texel within 2e-3 of the double-precision reference,
// A and B separately.
TEST_F(FbLutTest, MatchesCpuReference) {
  const Table& t = table();
  const auto texels = reference_texels(true);
  std::vector<test::FbAB> ref(texels.size());
  const auto start = std::chrono::steady_clock::now();
  parallel_for(texels.size(), [&](size_t k) { ref[k] = test::fb_reference(axis(texels[k].first), axis(texels[k].second)); });
  const double ref_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  double worst_a = 0, worst_b = 0;
  size_t at_a = 0, at_b = 0;
  for (size_t k = 0; k < texels.size(); ++k) {
    const auto [i, j] = texels[k];
    const double da = std::abs(t.a(i, j) - ref[k].a), db = std::abs(t.b(i, j) - ref[k].b);
    if (da > worst_a) worst_a = da, at_a = k;
    if (db > worst_b) worst_b = db, at_b = k;
    EXPECT_LE(da, 2e-3) << "A at column " << i << ", row " << j << ": " << t.a(i, j) << " vs " << ref[k].a;
    EXPECT_LE(db, 2e-3) << "B at column " << i << ", row " << j << ": " << t.b(i, j) << " vs " << ref[k].b;
  }
  std::printf("F_beta LUT vs CPU reference over %zu texels (reference %.1f s): max |dA| %.2e (cos %.4f, alpha %.4f), "
              "max |dB| %.2e (cos %.4f, alpha %.4f)\n",
              texels.size(), ref_s, worst_a, axis(texels[at_a].first), axis(texels[at_a].second), worst_b,
              axis(texels[at_b].first), axis(texels[at_b].second));
}

// (b) Finite everywhere, including α → 0 (row 0) and cos θ_o → 0 (column 0),
// and never negative.
TEST_F(FbLutTest, FiniteAndNonNegativeEverywhere) {
  const Table& t = table();
  ASSERT_EQ(t.v.size(), size_t{N} * N * 2);
  size_t bad = 0;
  for (uint32_t j = 0; j < N; ++j)
    for (uint32_t i = 0; i < N; ++i) {
      const bool ok = std::isfinite(t.a(i, j)) && std::isfinite(t.b(i, j)) && t.a(i, j) >= 0 && t.b(i, j) >= 0;
      if (!ok && bad++ < 10) ADD_FAILURE() << "texel " << i << ", " << j << ": " << t.a(i, j) << ", " << t.b(i, j);
    }
  EXPECT_EQ(bad, 0u);
}

// (c) A + B = F_beta(F0 = 1) ≤ 1: single-scattering GGX loses energy, never
// gains it. Every sample of the estimator weighs G2/G1 ≤ 1 and the shader sums
// E = A + B directly, so sampling noise cannot push it above 1 and only the
// final fp32 rounding can (~1e-7): the tolerance is 1e-6, tighter than the
// 1e-3 allowance for sampling noise the issue allows (svgf-fb relies on
// F_beta ≤ 1 + 1e-6 for F0 = 1).
TEST_F(FbLutTest, EnergyAtMostOne) {
  const Table& t = table();
  double worst = 0;
  uint32_t wi = 0, wj = 0;
  for (uint32_t j = 0; j < N; ++j)
    for (uint32_t i = 0; i < N; ++i) {
      const double e = double(t.a(i, j)) + t.b(i, j);
      if (e > worst) worst = e, wi = i, wj = j;
      EXPECT_LE(e, 1.0 + 1e-6) << "texel " << i << ", " << j;
    }
  std::printf("F_beta LUT: max A + B = %.7f (cos %.4f, alpha %.4f)\n", worst, axis(wi), axis(wj));
}

// (d) A + B → 1 as α → 0 (first row, α = 0.5/256) away from grazing
// (cos θ_o ≥ 0.1), and (A, B) → (1 − (1 − cos)^5, (1 − cos)^5): a mirror.
TEST_F(FbLutTest, SmoothLimitIsAMirror) {
  const Table& t = table();
  double worst_sum = 0, worst_split = 0;
  for (uint32_t i = 0; i < N; ++i) {
    if (axis(i) < 0.1) continue;
    const double e = double(t.a(i, 0)) + t.b(i, 0);
    const double s = std::pow(1 - axis(i), 5);
    worst_sum = std::max(worst_sum, std::abs(1 - e));
    worst_split = std::max({worst_split, std::abs(t.a(i, 0) - (1 - s)), std::abs(t.b(i, 0) - s)});
    EXPECT_NEAR(e, 1.0, 1e-2) << "column " << i;
    EXPECT_NEAR(t.b(i, 0), s, 1e-2) << "column " << i;
  }
  std::printf("F_beta LUT at alpha = %.5f, cos >= 0.1: max |1 - (A + B)| %.2e, max |(A, B) - mirror| %.2e\n", axis(0),
              worst_sum, worst_split);
}

// (e) F_beta(F0 = 1) = A + B is the white-furnace directional albedo
// ∫ D G2 / (4 cos θ_o) dw_i, computed by the reference as its own integral.
TEST_F(FbLutTest, WhiteFurnace) {
  const Table& t = table();
  const auto texels = reference_texels(false);
  std::vector<double> albedo(texels.size());
  parallel_for(texels.size(), [&](size_t k) {
    albedo[k] = test::fb_directional_albedo(axis(texels[k].first), axis(texels[k].second));
  });
  double worst = 0;
  for (size_t k = 0; k < texels.size(); ++k) {
    const auto [i, j] = texels[k];
    const double e = double(t.a(i, j)) + t.b(i, j);
    worst = std::max(worst, std::abs(e - albedo[k]));
    EXPECT_NEAR(e, albedo[k], 2e-3) << "column " << i << ", row " << j;
  }
  std::printf("F_beta LUT: white furnace over %zu texels, max |A + B - E| %.2e\n", texels.size(), worst);
}

// (f) fb_lut.glsl's dn_fb_lut against bilinear interpolation on the host:
// texel centres exactly, random points, the clamped edges, out-of-range and
// non-finite inputs.
TEST_F(FbLutTest, GlslLookupIsBilinear) {
  const Table& t = table();
  auto coord = [](float x) {
    double c = std::isnan(x) ? 0.0 : double(x) * N - 0.5;
    return std::clamp(c, 0.0, double(N - 1));
  };
  auto host = [&](float cos_o, float alpha, int component) {
    const double x = coord(cos_o), y = coord(alpha);
    const uint32_t i0 = std::min(static_cast<uint32_t>(x), N - 2), j0 = std::min(static_cast<uint32_t>(y), N - 2);
    const double tx = x - i0, ty = y - j0;
    auto at = [&](uint32_t i, uint32_t j) { return double(component ? t.b(i, j) : t.a(i, j)); };
    const double lo = at(i0, j0) * (1 - tx) + at(i0 + 1, j0) * tx;
    const double hi = at(i0, j0 + 1) * (1 - tx) + at(i0 + 1, j0 + 1) * tx;
    return lo * (1 - ty) + hi * ty;
  };
  std::vector<float> points;
  auto add = [&](float c, float a) {
    points.push_back(c);
    points.push_back(a);
  };
  const uint32_t centres[] = {0, 1, 7, 100, 254, 255};
  for (uint32_t j : centres)
    for (uint32_t i : centres) add(static_cast<float>(axis(i)), static_cast<float>(axis(j)));
  const size_t centre_count = points.size() / 2;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int k = 0; k < 2000; ++k) add(unit(rng), unit(rng));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float edges[] = {0.0f, 1e-4f, 0.5f / N, 1.0f - 0.5f / N, 1.0f, -0.25f, 1.5f, nan, inf, -inf};
  for (float c : edges)
    for (float a : edges) add(c, a);
  const auto got = probe(points);
  double worst = 0;
  for (size_t k = 0; k < points.size() / 2; ++k) {
    for (int comp = 0; comp < 2; ++comp) {
      const float g = got[2 * k + comp];
      const double want = host(points[2 * k], points[2 * k + 1], comp);
      ASSERT_TRUE(std::isfinite(g)) << "point " << points[2 * k] << ", " << points[2 * k + 1];
      worst = std::max(worst, std::abs(g - want));
      EXPECT_NEAR(g, want, 2e-6) << "point " << points[2 * k] << ", " << points[2 * k + 1] << " component " << comp;
    }
  }
  // At the texel centres the lookup returns the texel itself (up to fp32 rounding of the axis).
  for (size_t k = 0; k < centre_count; ++k) {
    const uint32_t i = centres[k % 6], j = centres[k / 6];
    EXPECT_NEAR(got[2 * k], t.a(i, j), 1e-6);
    EXPECT_NEAR(got[2 * k + 1], t.b(i, j), 1e-6);
  }
  std::printf("dn_fb_lut vs host bilinear over %zu points: max |difference| %.2e\n", points.size() / 2, worst);
}

}  // namespace
}  // namespace dn
