#include "render.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include <pmmintrin.h>
#include <xmmintrin.h>

#include "integrator.hpp"
#include "online_stats.hpp"
#include "scenes.hpp"

namespace dn::render {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kBackgroundDistance = 1e4f;  // where background "positions" are put, for their motion
constexpr int kMirrorChainLength = 8;

void put3(std::vector<float>& plane, size_t i, const glm::vec3& v) {
  if (plane.empty()) return;
  plane[3 * i] = v.x, plane[3 * i + 1] = v.y, plane[3 * i + 2] = v.z;
}

bool is_mirror_like(const SurfaceParams& s) {
  return s.has_specular && !s.has_diffuse && s.alpha < kSpecularAlphaThreshold;
}

// Diffuse albedo of a surface, or F0 for a metal: the colour that modulates its reflection.
glm::vec3 base_colour(const SurfaceParams& s) { return s.has_diffuse ? s.diffuse_albedo : s.f0; }

struct Planes {
  FrameBuffers& fb;
  const ChannelSet& want;
  void allocate(size_t n, int samples_stride) {
    auto alloc = [n](std::vector<float>& v, bool on, int comps) {
      if (on) v.assign(n * comps, 0.0f);
      else v.clear();
    };
    alloc(fb.radiance, true, 3);
    alloc(fb.diffuse, want.split, 3);
    alloc(fb.specular, want.split, 3);
    alloc(fb.emission, want.split, 3);
    alloc(fb.albedo, want.gbuffer, 3);
    alloc(fb.specular_f0, want.gbuffer, 3);
    alloc(fb.roughness, want.gbuffer, 1);
    alloc(fb.normal, want.gbuffer, 3);
    alloc(fb.depth, want.gbuffer, 1);
    alloc(fb.position, want.gbuffer, 3);
    alloc(fb.motion, want.motion, 2);
    alloc(fb.sample_count, want.sample_count, 1);
    alloc(fb.stat_count, want.statistics, 1);
    alloc(fb.stat_mean, want.statistics, 3);
    alloc(fb.stat_m2, want.statistics, 3);
    alloc(fb.stat_m3, want.statistics, 3);
    alloc(fb.stat_raw_mean, want.statistics, 3);
    alloc(fb.spec_hit_position, want.specular_hit, 3);
    alloc(fb.spec_hit_albedo, want.specular_hit, 3);
    alloc(fb.spec_hit_direction, want.specular_hit, 3);
    fb.samples_stride = want.record_samples ? samples_stride : 0;
    alloc(fb.samples, want.record_samples, samples_stride * 3);
  }
};

// Follows the mirror direction from a mirror-like primary hit to the first
// surface that is not mirror-like; writes the spec_hit_* planes.
void trace_mirror_chain(const Scene& scene, const Hit& primary, const glm::vec3& dir, size_t i, FrameBuffers& fb,
                        TraceContext& ctx) {
  glm::vec3 n = facing_normal(primary.normal, -dir);
  glm::vec3 d = glm::reflect(dir, n);
  put3(fb.spec_hit_direction, i, d);
  glm::vec3 origin = offset_origin(primary.position, n, d);
  for (int k = 0; k < kMirrorChainLength; ++k) {
    const Hit h = scene.intersect(origin, d, ctx);
    if (!h.found) {
      put3(fb.spec_hit_position, i, origin + d * kBackgroundDistance);
      return;
    }
    const SurfaceParams s = evaluate_material(scene.material_of(h), h.position);
    put3(fb.spec_hit_position, i, h.position);
    put3(fb.spec_hit_albedo, i, base_colour(s));
    if (!is_mirror_like(s)) return;
    n = facing_normal(h.normal, -d);
    d = glm::reflect(d, n);
    origin = offset_origin(h.position, n, d);
  }
}

struct PixelContext {
  const Scene& scene;
  const RenderSettings& settings;
  const CameraRays& rays;
  glm::mat4 view, view_projection, prev_view_projection;
  glm::vec2 jitter;
  int frame;
};

void render_pixel(const PixelContext& pc, int x, int y, FrameBuffers& fb, TraceContext& ctx) {
  const RenderSettings& st = pc.settings;
  const ChannelSet& want = st.channels;
  const Scene& scene = pc.scene;
  const size_t i = size_t(y) * st.width + x;
  const uint32_t pixel = static_cast<uint32_t>(i);
  const int count = samples_for_pixel(st.spp, st.seed, pc.frame, pixel);
  Rng rng(st.seed, static_cast<uint32_t>(pc.frame), pixel);

  // The G-buffer ray: pixel centre plus the frame's jitter. It is also sample 0.
  const glm::vec3 eye = pc.rays.eye();
  const glm::vec3 dir0 = pc.rays.direction(x + 0.5f + pc.jitter.x, y + 0.5f + pc.jitter.y);
  const Hit hit0 = scene.intersect(eye, dir0, ctx);
  const glm::vec3 world = hit0.found ? hit0.position : eye + dir0 * kBackgroundDistance;
  SurfaceParams surface0;
  if (hit0.found) surface0 = evaluate_material(scene.material_of(hit0), hit0.position);
  if (want.gbuffer) {
    put3(fb.position, i, world);
    if (hit0.found) {
      put3(fb.albedo, i, surface0.diffuse_albedo);
      put3(fb.specular_f0, i, surface0.f0);
      fb.roughness[i] = surface0.has_specular ? surface0.alpha : 1.0f;
      put3(fb.normal, i, facing_normal(hit0.normal, -dir0));
      fb.depth[i] = -(pc.view * glm::vec4(world, 1.0f)).z;
    } else {
      fb.roughness[i] = 1.0f;
      fb.depth[i] = kInf;
    }
  }
  if (want.motion) {
    // Unjittered in both frames: exact for a static scene, whatever the jitter.
    const glm::vec2 mv = project_to_pixel(pc.prev_view_projection, world, st.width, st.height) -
                         project_to_pixel(pc.view_projection, world, st.width, st.height);
    fb.motion[2 * i] = mv.x;
    fb.motion[2 * i + 1] = mv.y;
  }
  if (want.specular_hit && hit0.found && is_mirror_like(surface0)) trace_mirror_chain(scene, hit0, dir0, i, fb, ctx);

  const PathSettings path_settings{st.max_depth, st.next_event};
  PathResult sum;
  OnlineStats stats[3];
  for (int s = 0; s < count; ++s) {
    PathResult p;
    if (s == 0) {
      p = trace_path(scene, dir0, hit0, rng, path_settings, ctx);
    } else {
      // Further samples spread uniformly over the pixel (box filter), for references.
      const glm::vec2 u = rng.next2();
      const glm::vec3 dir = pc.rays.direction(x + u.x, y + u.y);
      p = trace_path(scene, dir, scene.intersect(eye, dir, ctx), rng, path_settings, ctx);
    }
    sum.diffuse += p.diffuse;
    sum.specular += p.specular;
    sum.emission += p.emission;
    const glm::vec3 total = p.total();
    if (want.statistics)
      for (int c = 0; c < 3; ++c) stats[c].add(total[c]);
    if (want.record_samples && s < fb.samples_stride) put3(fb.samples, i * fb.samples_stride + s, total);
  }
  if (count > 0) {
    const float inv = 1.0f / static_cast<float>(count);
    put3(fb.radiance, i, sum.total() * inv);
    put3(fb.diffuse, i, sum.diffuse * inv);
    put3(fb.specular, i, sum.specular * inv);
    put3(fb.emission, i, sum.emission * inv);
  } else {
    // Not sampled: no radiance, but emission is known from the G-buffer ray.
    put3(fb.emission, i, hit0.found ? scene.emitted(hit0, dir0) : scene.environment());
  }
  if (want.sample_count) fb.sample_count[i] = static_cast<float>(count);
  if (want.statistics) {
    fb.stat_count[i] = static_cast<float>(count);
    for (int c = 0; c < 3; ++c) {
      fb.stat_mean[3 * i + c] = stats[c].mean;
      fb.stat_m2[3 * i + c] = stats[c].m2;
      fb.stat_m3[3 * i + c] = stats[c].m3;
      fb.stat_raw_mean[3 * i + c] = stats[c].raw_mean;
    }
  }
}

}  // namespace

int samples_for_pixel(double spp, uint32_t seed, int frame, uint32_t pixel) {
  const double whole = std::floor(spp);
  const double fraction = spp - whole;
  int count = static_cast<int>(whole);
  if (fraction > 0.0) {
    // Its own hash, not the path's random stream, so the mask does not depend on rendering.
    const uint32_t h = hash_combine(hash_combine(seed ^ 0xA511E9B3u, static_cast<uint32_t>(frame)), pixel);
    if (to_unit_float(h) < fraction) ++count;
  }
  return count;
}

Camera frame_camera(int scene_id, int frame, const RenderSettings& settings) {
  Camera c = scene_camera(scene_id, frame, settings.width, settings.height);
  if (settings.jitter) c.jitter = halton_jitter(frame);
  return c;
}

FrameBuffers render_frame(const Scene& scene, const Camera& camera, const Camera& previous, int frame,
                          const RenderSettings& settings) {
  FrameBuffers fb;
  render_frame_into(scene, camera, previous, frame, settings, fb);
  return fb;
}

void render_frame_into(const Scene& scene, const Camera& camera, const Camera& previous, int frame,
                       const RenderSettings& settings, FrameBuffers& fb) {
  const auto t0 = std::chrono::steady_clock::now();
  fb.width = settings.width;
  fb.height = settings.height;
  Planes{fb, settings.channels}.allocate(size_t(settings.width) * settings.height,
                                         static_cast<int>(std::ceil(settings.spp)));
  const CameraRays rays(camera, settings.width, settings.height);
  const PixelContext pc{scene,
                        settings,
                        rays,
                        camera.view,
                        camera.projection * camera.view,
                        previous.projection * previous.view,
                        camera.jitter,
                        frame};

  const int tile = std::max(1, settings.tile);
  const int tiles_x = (settings.width + tile - 1) / tile, tiles_y = (settings.height + tile - 1) / tile;
  std::atomic<int> next_tile{0};
  std::atomic<uint64_t> rays_traced{0};
  auto worker = [&] {
    // Embree asks for flush-to-zero and denormals-are-zero on every tracing thread: denormals are slow.
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    TraceContext ctx;
    for (int t = next_tile++; t < tiles_x * tiles_y; t = next_tile++) {
      const int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
      for (int y = y0; y < std::min(y0 + tile, settings.height); ++y)
        for (int x = x0; x < std::min(x0 + tile, settings.width); ++x) render_pixel(pc, x, y, fb, ctx);
    }
    rays_traced += ctx.rays;
  };
  const unsigned threads =
      settings.threads > 0 ? static_cast<unsigned>(settings.threads) : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned k = 1; k < threads; ++k) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  fb.rays = rays_traced;
  fb.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

bool primary_position(const Scene& scene, const Camera& camera, int width, int height, float px, float py,
                      glm::vec3& position) {
  const CameraRays rays(camera, width, height);
  TraceContext ctx;
  const Hit h = scene.intersect(rays.eye(), rays.direction(px, py), ctx);
  if (h.found) position = h.position;
  return h.found;
}

}  // namespace dn::render
