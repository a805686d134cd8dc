#include "render.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <thread>

#include <pmmintrin.h>
#include <xmmintrin.h>

#include "bsdf.hpp"
#include "dn/protocol/channels.hpp"
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

// The roughness channel's value for one surface: its specular lobe's alpha, 1 without one.
float roughness_of(const SurfaceParams& s) { return s.has_specular ? s.alpha : 1.0f; }

// A pure mirror: a mirror-class specular lobe and nothing under it, so its
// whole reflection is the mirror image (a coated surface also shows its base).
bool is_mirror_like(const SurfaceParams& s) {
  return s.has_specular && !s.has_diffuse && s.alpha < kMirrorRoughness;
}

// Diffuse albedo of a surface, or F0 for a metal: the colour that modulates its reflection.
glm::vec3 base_colour(const SurfaceParams& s) { return s.has_diffuse ? s.diffuse_albedo : s.f0; }

struct Planes {
  FrameBuffers& fb;
  const ChannelSet& want;
  void allocate(size_t n, int samples_stride, int extra_samples) {
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
    fb.statistics_demodulated = want.statistics && want.statistics_demodulated;
    alloc(fb.reflection_position, want.reflection, 3);
    alloc(fb.reflection_albedo, want.reflection, 3);
    alloc(fb.reflection_normal, want.reflection, 3);
    alloc(fb.reflection_direction, want.reflection, 3);
    alloc(fb.reflection_depth, want.reflection, 1);
    alloc(fb.reflection_distance, want.reflection, 1);
    alloc(fb.reflection_footprint, want.reflection, 1);
    fb.extra.resize(size_t(extra_samples));
    for (auto& e : fb.extra) {
      alloc(e.radiance, true, 3);
      alloc(e.diffuse, want.split, 3);
      alloc(e.specular, want.split, 3);
      alloc(e.normal, true, 3);
      alloc(e.depth, true, 1);
      alloc(e.offset, true, 2);
    }
    fb.samples_stride = want.record_samples ? samples_stride : 0;
    alloc(fb.samples, want.record_samples, samples_stride * 3);
    alloc(fb.sample_albedo, want.record_samples, samples_stride * 3);
  }
};

struct PixelContext {
  const Scene& scene;
  const RenderSettings& settings;
  const CameraRays& rays;
  glm::mat4 view, view_projection, prev_view_projection;
  glm::vec2 jitter;
  int frame;
};

// Ray differentials (Igehy 1999): the derivatives of a ray's position and
// direction with respect to the pixel position x and y.
struct RayDifferentials {
  glm::vec3 dp[2]{glm::vec3(0.0f), glm::vec3(0.0f)};
  glm::vec3 dd[2]{glm::vec3(0.0f), glm::vec3(0.0f)};
};

// Keeps a denominator's sign but away from 0, for rays that graze a surface.
float away_from_zero(float v) { return v < 0.0f ? std::min(v, -1e-6f) : std::max(v, 1e-6f); }

// Transfer along a ray of unit direction d to its hit at distance t on a
// surface of normal n (Igehy Eq. 10-12): the hit moves within the tangent plane.
void transfer(RayDifferentials& rd, const glm::vec3& d, float t, const glm::vec3& n) {
  for (int k = 0; k < 2; ++k) {
    const glm::vec3 q = rd.dp[k] + t * rd.dd[k];
    rd.dp[k] = q - (glm::dot(q, n) / away_from_zero(glm::dot(d, n))) * d;
  }
}

// Mirror reflection r = d - 2 (d.n) n about the facing normal n, whose
// derivative is curvature * dp (a sphere's normal turns with the position, a
// plane's does not; Igehy Eq. 14-15).
void reflect_differentials(RayDifferentials& rd, const glm::vec3& d, const glm::vec3& n, float curvature) {
  for (int k = 0; k < 2; ++k) {
    const glm::vec3 dn = curvature * rd.dp[k];
    const float d_dn = glm::dot(rd.dd[k], n) + glm::dot(d, dn);
    rd.dd[k] -= 2.0f * (glm::dot(d, n) * dn + d_dn * n);
  }
}

// What a mirror in the chain passes on: its Fresnel reflectance at the
// chain's incidence cosine, as Bsdf weighs its specular samples (F at the
// half vector, which is the normal for a mirror; G2 / G1 is 1 at alpha 0).
glm::vec3 mirror_reflectance(const SurfaceParams& s, float cos_incidence) {
  return fresnel_schlick(s.f0, cos_incidence);
}

// The primary hit of one pixel's sample 0 ray, as the reflection features need it.
struct PrimaryHit {
  const Hit& hit;
  glm::vec3 dir;     // the camera ray, unit
  glm::vec3 normal;  // facing the camera
  float depth;       // linear view depth
  glm::vec2 pixel;   // continuous pixel position of the ray (centre + jitter)
};

// The footprint of the representative ray r at its hit `h` (channel 21): the
// camera ray's differentials transferred to the primary hit, reflected, and
// transferred to h; (|dP/dx| + |dP/dy|) / 2 there.
float representative_footprint(const PixelContext& pc, const PrimaryHit& p, const glm::vec3& r, const Hit& h) {
  RayDifferentials rd;  // from the eye: the position does not move with the pixel
  pc.rays.direction_differentials(p.pixel.x, p.pixel.y, rd.dd[0], rd.dd[1]);
  transfer(rd, p.dir, p.hit.t, p.normal);
  reflect_differentials(rd, p.dir, p.normal, glm::dot(p.normal, p.hit.normal) * pc.scene.curvature(p.hit));
  transfer(rd, r, glm::distance(p.hit.position, h.position), h.normal);
  return 0.5f * (glm::length(rd.dp[0]) + glm::length(rd.dp[1]));
}

// The mirror chain (channels 15-18) from a mirror pixel's primary hit along r,
// whose first segment's hit `h` is already traced: reflects off every pure
// mirror it meets, up to kMirrorChainLength segments, and describes the
// surface where it stops. A chain that leaves the scene leaves albedo, normal
// and depth 0.
void mirror_chain(const Scene& scene, const PrimaryHit& p, glm::vec3 d, Hit h, size_t i, FrameBuffers& fb,
                  TraceContext& ctx) {
  glm::vec3 from = p.hit.position;
  glm::vec3 reflectance(1.0f);  // of the mirrors after the primary
  float length = 0.0f;
  for (int segment = 1;; ++segment) {
    if (!h.found) {
      put3(fb.reflection_position, i, from + d * kBackgroundDistance);
      return;
    }
    length += glm::distance(from, h.position);
    const SurfaceParams s = evaluate_material(scene.material_of(h), h.position);
    const glm::vec3 n = facing_normal(h.normal, -d);
    if (!is_mirror_like(s) || segment == kMirrorChainLength) {
      put3(fb.reflection_position, i, h.position);
      put3(fb.reflection_normal, i, n);
      put3(fb.reflection_albedo, i, base_colour(s) * reflectance);
      // Virtual depth: the chain unfolded onto the primary ray scales depth like distance.
      fb.reflection_depth[i] = p.depth * (p.hit.t + length) / p.hit.t;
      return;
    }
    reflectance *= mirror_reflectance(s, glm::dot(-d, n));
    from = h.position;
    d = glm::reflect(d, n);
    h = scene.intersect(offset_origin(from, n, d), d, ctx);
  }
}

// The reflection features of one pixel of class `cls` (docs/protocol.md §7.5):
// the representative ray (the view ray mirrored about the primary normal) at
// mirror and glossy pixels, the mirror chain, which continues it, at mirror
// pixels. Other pixels keep the zeros the planes were allocated with, and
// trace nothing.
void reflection_features(const PixelContext& pc, const PrimaryHit& p, ReflectionClass cls, size_t i,
                         FrameBuffers& fb, TraceContext& ctx) {
  if (cls == ReflectionClass::None) return;
  const glm::vec3 r = glm::reflect(p.dir, p.normal);
  put3(fb.reflection_direction, i, r);
  const Hit h = pc.scene.intersect(offset_origin(p.hit.position, p.normal, r), r, ctx);
  if (h.found) {
    fb.reflection_distance[i] = glm::distance(p.hit.position, h.position);
    fb.reflection_footprint[i] = representative_footprint(pc, p, r, h);
  }
  if (cls == ReflectionClass::Mirror) mirror_chain(pc.scene, p, r, h, i, fb, ctx);
}

// The hits through the pixel corners of one tile, (w + 1) x (h + 1), shared
// by the pixels around each corner (built by build_tile_corners below).
struct TileCorners {
  int x0 = 0, y0 = 0, stride = 0;
  std::vector<Hit> hits;
  std::vector<uint8_t> known;  // build state: hits[i] is set
  // A plain block: on one surface whose material has no maps, or on one
  // planar face whose four corners share one region of the material's maps,
  // so every pixel's footprint has the block's material values (the region
  // and the block are convex); on a face, also one facing normal.
  struct PlainBlock {
    SurfaceParams params;
    bool planar = false;
    glm::vec3 normal{0.0f};  // planar: the face's normal towards the eye
  };
  std::vector<PlainBlock> blocks;
  std::vector<int> plain;  // per pixel (w x h): index into blocks, or -1
  const Hit& at(int x, int y) const { return hits[size_t(y - y0) * stride + (x - x0)]; }
  const PlainBlock* plain_at(int x, int y) const {
    const int b = plain[size_t(y - y0) * (stride - 1) + (x - x0)];
    return b < 0 ? nullptr : &blocks[size_t(b)];
  }
};

// Whether two hits lie on the same convex surface: one sphere, or one planar
// face of a quad or box (same geometry, same plane).
bool same_surface(const Scene& scene, const Hit& a, const Hit& b) {
  if (!a.found || !b.found || a.geometry != b.geometry) return false;
  if (scene.is_sphere(a)) return true;
  return glm::dot(a.normal, b.normal) > 0.9999f &&
         std::fabs(glm::dot(b.position - a.position, a.normal)) <= 1e-4f * (a.t + b.t);
}

// The tile's corner hits. A block of pixels whose four outer corners and
// every pixel's sample-0 hit (`centres`, row-major over the tile) lie on one
// convex surface lies on it entirely: the surface's screen projection is
// convex, and an occluder in front of part of it would cover a pixel centre
// unless it is smaller than a pixel (the case footprint_gbuffer misses too).
// Its inner corners are then intersected with that surface analytically
// instead of traced; a block that fails is split in four, down to single
// pixels, whose corners are traced.
void build_tile_corners(const PixelContext& pc, int x0, int y0, int w, int h, const std::vector<Hit>& centres,
                        TileCorners& tc, TraceContext& ctx) {
  const Scene& scene = pc.scene;
  tc.x0 = x0, tc.y0 = y0, tc.stride = w + 1;
  tc.hits.assign(size_t(w + 1) * (h + 1), Hit{});
  tc.known.assign(tc.hits.size(), 0);
  tc.plain.assign(size_t(w) * h, -1);
  tc.blocks.clear();
  const glm::vec3 eye = pc.rays.eye();
  auto traced = [&](int cx, int cy) -> const Hit& {
    const size_t i = size_t(cy) * tc.stride + cx;
    if (!tc.known[i]) {
      tc.hits[i] = scene.intersect(eye, pc.rays.direction(float(x0 + cx), float(y0 + cy)), ctx);
      tc.known[i] = 1;
    }
    return tc.hits[i];
  };
  // Splits block [bx0, bx1] x [by0, by1] (tile corner coordinates, more than
  // one pixel) in four, or in two when it is one pixel thick, and calls f on
  // each part.
  auto for_parts = [](int bx0, int by0, int bx1, int by1, auto&& f) {
    const int mx = (bx0 + bx1) / 2, my = (by0 + by1) / 2;
    if (bx1 - bx0 > 1 && by1 - by0 > 1) {
      f(bx0, by0, mx, my);
      f(mx, by0, bx1, my);
      f(bx0, my, mx, by1);
      f(mx, my, bx1, by1);
    } else if (bx1 - bx0 > 1) {
      f(bx0, by0, mx, by1);
      f(mx, by0, bx1, by1);
    } else {
      f(bx0, by0, bx1, my);
      f(bx0, my, bx1, by1);
    }
  };
  const auto at = [&](int cx, int cy) -> const Hit& { return tc.hits[size_t(cy) * tc.stride + cx]; };
  // Within a block on one surface whose corners are all set: the largest
  // parts whose four corners share one region of the material's maps are
  // plain blocks (a material without maps: the whole block).
  auto mark_plain = [&](auto&& self, const Material& m, int bx0, int by0, int bx1, int by1) -> void {
    const Hit& a = at(bx0, by0);
    const bool one_region = same_material_region(m, a.position, at(bx1, by0).position) &&
                            same_material_region(m, a.position, at(bx0, by1).position) &&
                            same_material_region(m, a.position, at(bx1, by1).position);
    if (one_region) {
      const bool planar = !scene.is_sphere(a);
      tc.blocks.push_back({evaluate_material(m, a.position), planar,
                           planar ? facing_normal(a.normal, eye - a.position) : glm::vec3(0.0f)});
      for (int py = by0; py < by1; ++py)
        for (int px = bx0; px < bx1; ++px) tc.plain[size_t(py) * w + px] = int(tc.blocks.size() - 1);
      return;
    }
    if (bx1 - bx0 <= 1 && by1 - by0 <= 1) return;
    for_parts(bx0, by0, bx1, by1, [&](int x0p, int y0p, int x1p, int y1p) { self(self, m, x0p, y0p, x1p, y1p); });
  };
  // Blocks [bx0, bx1] x [by0, by1] in tile corner coordinates.
  auto fill = [&](auto&& self, int bx0, int by0, int bx1, int by1) -> void {
    const Hit& a = traced(bx0, by0);
    const bool corners_agree = same_surface(scene, a, traced(bx1, by0)) &&
                               same_surface(scene, a, traced(bx0, by1)) &&
                               same_surface(scene, a, traced(bx1, by1));
    if (bx1 - bx0 <= 1 && by1 - by0 <= 1) return;
    bool uniform = corners_agree;
    for (int py = by0; uniform && py < by1; ++py)
      for (int px = bx0; uniform && px < bx1; ++px) uniform = same_surface(scene, a, centres[size_t(py) * w + px]);
    if (!uniform) {
      for_parts(bx0, by0, bx1, by1, [&](int x0p, int y0p, int x1p, int y1p) { self(self, x0p, y0p, x1p, y1p); });
      return;
    }
    const Hit surface = a;
    for (int cy = by0; cy <= by1; ++cy)
      for (int cx = bx0; cx <= bx1; ++cx) {
        const size_t i = size_t(cy) * tc.stride + cx;
        if (tc.known[i]) continue;
        const Hit hit = scene.intersect_surface(surface, eye, pc.rays.direction(float(x0 + cx), float(y0 + cy)));
        if (hit.found) {
          tc.hits[i] = hit;
          tc.known[i] = 1;
        } else {
          traced(cx, cy);  // grazing rounding: trace it
        }
      }
    const Material& m = scene.material_of(surface);
    const bool unmapped = m.albedo_map == Pattern::None && m.roughness_map == Pattern::None;
    if (unmapped || !scene.is_sphere(surface)) mark_plain(mark_plain, m, bx0, by0, bx1, by1);
  };
  fill(fill, 0, 0, w, h);
}

// Area-weighted sums of the averaged channels over a pixel's footprint.
struct FootprintSum {
  glm::vec3 albedo{0.0f}, f0{0.0f}, normal{0.0f};
  float roughness = 0.0f;
  void add(const SurfaceParams& s, const glm::vec3& facing_normal, float area) {
    albedo += s.diffuse_albedo * area;
    f0 += s.f0 * area;
    roughness += (s.has_specular ? s.alpha : 1.0f) * area;
    normal += facing_normal * area;
  }
  void add_background(float area) { roughness += area; }
};

// One pixel whose corners lie on one convex surface: the square
// [x0, x0 + size)^2 with corner hits c[0..3] (x0y0, x1y0, x0y1, x1y1) on it.
struct SurfaceFootprint {
  const PixelContext& pc;
  const Hit& surface;
  const Material& material;
  int max_depth;
  Rng& rng;
  TraceContext& ctx;
  FootprintSum& sum;

  Hit point(float px, float py) const { return pc.scene.intersect_surface(surface, pc.rays.eye(), pc.rays.direction(px, py)); }

  glm::vec3 facing(const Hit& h) const { return facing_normal(h.normal, pc.rays.eye() - h.position); }

  // A square on a planar face whose corners fall in exactly two regions of
  // the material's maps, one straight boundary between them: the boundary is
  // a plane of the pattern meeting the face, so its screen image is a line.
  // It crosses the two edges whose ends differ; each crossing is found by
  // bisection along its edge (to 2^-8 of the edge), and the square's area
  // splits exactly between the two regions. False (nothing added) when that
  // shape does not hold: two diagonal corners alike, a third region met on an
  // edge, or a sphere (its boundaries are curves on screen).
  bool two_regions(float x0, float y0, float size, const Hit (&c)[4]) {
    if (pc.scene.is_sphere(surface)) return false;
    // Corners in cyclic order around the square, with their screen positions.
    const int order[4] = {0, 1, 3, 2};
    const glm::vec2 at[4] = {{x0, y0}, {x0 + size, y0}, {x0, y0 + size}, {x0 + size, y0 + size}};
    const MaterialRegion region_a = material_region(material, c[0].position);
    MaterialRegion region_b;
    bool in_a[4];
    int b = -1;
    for (int k = 0; k < 4; ++k) {
      const MaterialRegion r = material_region(material, c[k].position);
      in_a[k] = r == region_a;
      if (in_a[k]) continue;
      if (b < 0) {
        b = k;
        region_b = r;
      } else if (!(r == region_b)) {
        return false;  // a third region at a corner
      }
    }
    if (b < 0) return false;
    // Region A as a polygon: its corners and the two crossings, in cyclic order.
    glm::vec2 poly[6];
    int n = 0, crossings = 0;
    for (int e = 0; e < 4; ++e) {
      const int i = order[e], j = order[(e + 1) % 4];
      if (in_a[i]) poly[n++] = at[i];
      if (in_a[i] == in_a[j]) continue;
      if (++crossings > 2) return false;
      // Bisection between the A end and the B end of the edge.
      glm::vec2 lo = in_a[i] ? at[i] : at[j], hi = in_a[i] ? at[j] : at[i];
      for (int it = 0; it < 8; ++it) {
        const glm::vec2 mid = 0.5f * (lo + hi);
        const Hit h = point(mid.x, mid.y);
        if (!h.found) return false;
        const MaterialRegion r = material_region(material, h.position);
        if (r == region_a) lo = mid;
        else if (r == region_b) hi = mid;
        else return false;  // a third region on this edge
      }
      poly[n++] = 0.5f * (lo + hi);
    }
    if (crossings != 2) return false;
    double twice = 0.0;  // shoelace
    for (int k = 0; k < n; ++k) {
      const glm::vec2 p = poly[k], q = poly[(k + 1) % n];
      twice += double(p.x) * q.y - double(q.x) * p.y;
    }
    const float area = size * size, area_a = std::min(area, float(0.5 * std::fabs(twice)));
    const glm::vec3 nrm = glm::normalize(facing(c[0]) + facing(c[1]) + facing(c[2]) + facing(c[3]));
    sum.add(evaluate_material(material, c[0].position), nrm, area_a);
    sum.add(evaluate_material(material, c[b].position), nrm, area - area_a);
    return true;
  }

  // A square whose corners share one region of the material's maps is
  // constant (the region is convex, and so is the square's footprint on a
  // face); one cut by a single straight boundary splits exactly
  // (two_regions); otherwise split it in four, down to max_depth, where a
  // square that still holds an edge takes one jittered sample.
  void square(float x0, float y0, float size, const Hit (&c)[4], int depth) {
    const float area = size * size;
    bool found = true, same = true;
    for (const Hit& h : c) found = found && h.found;
    if (found)
      for (int k = 1; k < 4 && same; ++k) same = same_material_region(material, c[0].position, c[k].position);
    if (found && same) {
      const glm::vec3 n = facing(c[0]) + facing(c[1]) + facing(c[2]) + facing(c[3]);
      sum.add(evaluate_material(material, c[0].position), glm::normalize(n), area);
      return;
    }
    if (found && two_regions(x0, y0, size, c)) return;
    if (depth == max_depth || !found) {
      const glm::vec2 u = rng.next2();
      const glm::vec3 dir = pc.rays.direction(x0 + u.x * size, y0 + u.y * size);
      Hit h = pc.scene.intersect_surface(surface, pc.rays.eye(), dir);
      if (!h.found) h = pc.scene.intersect(pc.rays.eye(), dir, ctx);  // a ray grazing a sphere
      if (!h.found) return sum.add_background(area);
      return sum.add(evaluate_material(pc.scene.material_of(h), h.position), facing_normal(h.normal, -dir), area);
    }
    const float half = 0.5f * size;
    const Hit top = point(x0 + half, y0), left = point(x0, y0 + half), mid = point(x0 + half, y0 + half),
              right = point(x0 + size, y0 + half), bottom = point(x0 + half, y0 + size);
    square(x0, y0, half, {c[0], top, left, mid}, depth + 1);
    square(x0 + half, y0, half, {top, c[1], mid, right}, depth + 1);
    square(x0, y0 + half, half, {left, mid, c[2], bottom}, depth + 1);
    square(x0 + half, y0 + half, half, {mid, right, bottom, c[3]}, depth + 1);
  }
};

// The material channels as pixel-footprint averages: albedo, specular_f0,
// roughness and normal over the pixel's box footprint [x, x+1) x [y, y+1),
// the footprint the radiance samples beyond the first (and so the
// references) are spread over. Unjittered: the frame's jitter moves only the
// radiance sample 0 ray and the point-sampled channels (depth, position,
// motion). Background counts with the background's values (albedo and F0 0,
// roughness 1), so a silhouette pixel's albedo is its coverage-weighted mean,
// as its converged radiance is. The normal is the renormalised mean facing
// normal of the surfaces in the footprint, and 0 when the point-sampled depth
// says background (normal 0 <=> depth +inf, as before). Random numbers depend
// on (seed, pixel) but not on the frame: a still camera gets the same
// G-buffers every frame (no flicker from them), and they are a stream of
// their own, so the radiance samples are those of the point-sampled G-buffer.
//
// Three cases, by the hits through the pixel's four corners (shared by
// neighbouring pixels, build_tile_corners):
// - the pixel lies in a plain block (TileCorners::plain): one material
//   evaluation;
// - all four hit one convex surface (one sphere, or one face of a quad or
//   box): the whole footprint lies on it, as its screen projection is convex.
//   No more rays: sub-squares are intersected with the surface analytically
//   and split where the material's maps change, down to 1/(4K) of a pixel
//   (1/16 by default), with one jittered sample in each finest square that
//   still holds a texture edge. Exact where the maps are constant, so the
//   whole face of a plain material costs one material evaluation. (An object
//   smaller than the pixel that covers none of its corners is missed.)
// - otherwise (a silhouette or a crease in the pixel): a K x K jittered
//   stratified grid of G-buffer rays (primary hit + material, no path).
void footprint_gbuffer(const PixelContext& pc, int x, int y, const TileCorners& corners, bool centre_hit,
                       const glm::vec3& centre_normal, size_t i, FrameBuffers& fb, TraceContext& ctx) {
  const Scene& scene = pc.scene;
  const int k = pc.settings.gbuffer_grid;
  const Hit& c00 = corners.at(x, y);
  const Hit(&c)[4] = {c00, corners.at(x + 1, y), corners.at(x, y + 1), corners.at(x + 1, y + 1)};
  Rng rng(pc.settings.seed ^ 0x6B0FF5E7u, 0x9B1D5EEDu, static_cast<uint32_t>(i));
  FootprintSum sum;
  if (const auto* block = corners.plain_at(x, y)) {
    // What SurfaceFootprint::square does for a square in one region, without its tests.
    glm::vec3 n = block->normal;
    if (!block->planar) {
      const glm::vec3 eye = pc.rays.eye();
      n = glm::normalize(facing_normal(c[0].normal, eye - c[0].position) + facing_normal(c[1].normal, eye - c[1].position) +
                         facing_normal(c[2].normal, eye - c[2].position) + facing_normal(c[3].normal, eye - c[3].position));
    }
    sum.add(block->params, n, 1.0f);
  } else if (same_surface(scene, c00, c[1]) && same_surface(scene, c00, c[2]) && same_surface(scene, c00, c[3])) {
    int depth = 0;
    while ((1 << depth) < 4 * k) ++depth;
    SurfaceFootprint{pc, c00, scene.material_of(c00), depth, rng, ctx, sum}.square(float(x), float(y), 1.0f, c, 0);
  } else {
    const float cell = 1.0f / static_cast<float>(k);
    const float area = cell * cell;
    const glm::vec3 eye = pc.rays.eye();
    for (int sy = 0; sy < k; ++sy)
      for (int sx = 0; sx < k; ++sx) {
        const glm::vec2 u = rng.next2();
        const glm::vec3 dir = pc.rays.direction(x + (sx + u.x) * cell, y + (sy + u.y) * cell);
        const Hit h = scene.intersect(eye, dir, ctx);
        if (h.found) sum.add(evaluate_material(scene.material_of(h), h.position), facing_normal(h.normal, -dir), area);
        else sum.add_background(area);
      }
  }
  put3(fb.albedo, i, sum.albedo);
  put3(fb.specular_f0, i, sum.f0);
  fb.roughness[i] = sum.roughness;
  if (centre_hit) {
    const float len = glm::length(sum.normal);
    put3(fb.normal, i, len > 1e-6f ? sum.normal / len : centre_normal);
  }
}

// The ray through pixel (x, y)'s centre plus the frame's jitter: the
// G-buffer ray and radiance sample 0.
glm::vec3 centre_direction(const PixelContext& pc, int x, int y) {
  return pc.rays.direction(x + 0.5f + pc.jitter.x, y + 0.5f + pc.jitter.y);
}

// `centre`: the hit of centre_direction if already traced (footprint tiles), else null.
void render_pixel(const PixelContext& pc, int x, int y, const TileCorners& corners, const Hit* centre,
                  FrameBuffers& fb, TraceContext& ctx) {
  const RenderSettings& st = pc.settings;
  const ChannelSet& want = st.channels;
  const Scene& scene = pc.scene;
  const size_t i = size_t(y) * st.width + x;
  const uint32_t pixel = static_cast<uint32_t>(i);
  const int count = samples_for_pixel(st.spp, st.seed, pc.frame, pixel, st.width, st.spp_schedule);
  Rng rng(st.seed, static_cast<uint32_t>(pc.frame), pixel);

  // The G-buffer ray: pixel centre plus the frame's jitter. It is also sample 0.
  const glm::vec3 eye = pc.rays.eye();
  const glm::vec3 dir0 = centre_direction(pc, x, y);
  const Hit hit0 = centre ? *centre : scene.intersect(eye, dir0, ctx);
  const glm::vec3 world = hit0.found ? hit0.position : eye + dir0 * kBackgroundDistance;
  SurfaceParams surface0;
  if (hit0.found) surface0 = evaluate_material(scene.material_of(hit0), hit0.position);
  if (want.gbuffer) {
    // Point-sampled at the radiance sample 0 ray (centre + jitter): depth and
    // position. Averaging them across a silhouette would invent geometry that
    // is in neither surface; the motion below comes from the same point.
    put3(fb.position, i, world);
    fb.depth[i] = hit0.found ? -(pc.view * glm::vec4(world, 1.0f)).z : kInf;
    if (st.gbuffer_grid > 0) {
      footprint_gbuffer(pc, x, y, corners, hit0.found, hit0.found ? facing_normal(hit0.normal, -dir0) : glm::vec3(0.0f), i,
                        fb, ctx);
    } else if (hit0.found) {
      put3(fb.albedo, i, surface0.diffuse_albedo);
      put3(fb.specular_f0, i, surface0.f0);
      fb.roughness[i] = roughness_of(surface0);
      put3(fb.normal, i, facing_normal(hit0.normal, -dir0));
    } else {
      fb.roughness[i] = 1.0f;
    }
  }
  if (want.motion) {
    // Unjittered in both frames: exact for a static scene, whatever the jitter.
    const glm::vec2 mv = project_to_pixel(pc.prev_view_projection, world, st.width, st.height) -
                         project_to_pixel(pc.view_projection, world, st.width, st.height);
    fb.motion[2 * i] = mv.x;
    fb.motion[2 * i + 1] = mv.y;
  }
  if (want.reflection && hit0.found) {
    // Classed by the roughness the frame sends (a footprint average), so the
    // features are there wherever the server's classes read them.
    const float roughness = want.gbuffer ? fb.roughness[i] : roughness_of(surface0);
    const float depth = -(pc.view * glm::vec4(hit0.position, 1.0f)).z;
    const PrimaryHit p{hit0, dir0, facing_normal(hit0.normal, -dir0), depth,
                       glm::vec2(x + 0.5f + pc.jitter.x, y + 0.5f + pc.jitter.y)};
    reflection_features(pc, p, reflection_class(roughness), i, fb, ctx);
  }

  const PathSettings path_settings{st.max_depth, st.next_event};
  PathResult sum;
  OnlineStats stats[3];
  const bool want_albedo = want.record_samples || (want.statistics && want.statistics_demodulated);
  for (int s = 0; s < count; ++s) {
    glm::vec3 dir = dir0;
    Hit hit = hit0;
    if (s > 0) {
      // Further samples spread uniformly over the pixel (box filter), for references.
      const glm::vec2 u = rng.next2();
      dir = pc.rays.direction(x + u.x, y + u.y);
      hit = scene.intersect(eye, dir, ctx);
    }
    const PathResult p = trace_path(scene, dir, hit, rng, path_settings, ctx);
    sum.diffuse += p.diffuse;
    sum.specular += p.specular;
    sum.emission += p.emission;
    const glm::vec3 total = p.total();
    // The diffuse albedo of this sample's own primary hit (a miss: the background's, 0).
    glm::vec3 albedo(0.0f);
    if (want_albedo && hit.found)
      albedo = s == 0 ? surface0.diffuse_albedo : evaluate_material(scene.material_of(hit), hit.position).diffuse_albedo;
    if (want.statistics)
      for (int c = 0; c < 3; ++c) {
        const float v = sanitize_sample(total[c]);
        stats[c].add(want.statistics_demodulated ? v / protocol::demodulation_albedo(albedo[c]) : v);
      }
    if (want.record_samples && s < fb.samples_stride) {
      put3(fb.samples, i * fb.samples_stride + s, total);
      put3(fb.sample_albedo, i * fb.samples_stride + s, albedo);
    }
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
  for (size_t j = 0; j < fb.extra.size(); ++j) {
    // After sample 0's path, from the same stream: a render without extra
    // samples keeps its ordinary planes bit for bit.
    FrameBuffers::ExtraSample& e = fb.extra[j];
    const glm::vec2 offset = rng.next2() - 0.5f;
    const glm::vec3 dir = pc.rays.direction(x + 0.5f + pc.jitter.x + offset.x, y + 0.5f + pc.jitter.y + offset.y);
    const Hit hit = scene.intersect(eye, dir, ctx);
    const PathResult p = trace_path(scene, dir, hit, rng, path_settings, ctx);
    put3(e.radiance, i, p.total());
    if (!e.diffuse.empty()) {
      put3(e.diffuse, i, p.diffuse);
      put3(e.specular, i, p.specular);
    }
    put3(e.normal, i, hit.found ? facing_normal(hit.normal, -dir) : glm::vec3(0.0f));
    e.depth[i] = hit.found ? -(pc.view * glm::vec4(hit.position, 1.0f)).z : kInf;
    e.offset[2 * i] = offset.x;
    e.offset[2 * i + 1] = offset.y;
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

constexpr int kMaxStratifiedPeriod = 1024;

// Index of (x, y) in the 2^m x 2^m Bayer ordered-dither matrix (only the low m bits of
// x and y count). The tile's coarse bits become the index's low bits, so every aligned
// run of 2^j consecutive indices is a lattice spread evenly over the tile.
uint32_t bayer_index(uint32_t x, uint32_t y, int m) {
  uint32_t index = 0;
  for (int level = 0; level < m; ++level) {
    const uint32_t pair = (((x ^ y) >> level) & 1u) << 1 | ((y >> level) & 1u);
    index |= pair << (2 * (m - 1 - level));
  }
  return index;
}

// Squared length of the shortest vector in coset j of the lattice {(x, y): x + c y = 0 mod k};
// for j = 0 its shortest nonzero vector.
long coset_distance2(int j, int c, int k) {
  auto fold = [k](long r) {
    r %= k;
    if (r < 0) r += k;
    return std::min(r, k - r);
  };
  long best = j == 0 ? long(k) * k : fold(j) * fold(j);
  for (long y = 1; y * y < best; ++y)
    for (const long dy : {y, -y}) {
      const long x = fold(j - c * dy);
      best = std::min(best, y * y + x * x);
    }
  return best;
}

// For k not a power of two, frame t samples the pixels with x + c y + shift = g t (mod k):
// c makes each frame's pixels the lattice with the longest shortest vector (no clumps,
// neighbours differ), g (coprime with k) puts consecutive frames' pixels far apart.
struct LatticeSchedule {
  uint32_t c, g;
};

LatticeSchedule lattice_schedule(int k) {
  // c | g << 16, found once per k; 0: not yet. Racing threads store the same value.
  static std::array<std::atomic<uint32_t>, kMaxStratifiedPeriod + 1> cache{};
  uint32_t packed = cache[k].load(std::memory_order_relaxed);
  if (packed == 0) {
    int best_c = 1, best_g = 1;
    long best = 0;
    for (int c = 1; c < k; ++c)
      if (const long d = coset_distance2(0, c, k); d > best) best = d, best_c = c;
    best = 0;
    for (int g = 1; g < k; ++g)
      if (std::gcd(g, k) == 1)
        if (const long d = coset_distance2(g, best_c, k); d > best) best = d, best_g = g;
    packed = uint32_t(best_c) | uint32_t(best_g) << 16;
    cache[k].store(packed, std::memory_order_relaxed);
  }
  return {packed & 0xFFFFu, packed >> 16};
}

// Whether pixel (x, y) takes the extra sample at `frame` under the stratified schedule of period k.
bool stratified_extra_sample(int k, uint32_t seed, int frame, uint32_t x, uint32_t y) {
  const uint32_t h = hash_combine(seed ^ 0x5B1D0F3Cu, static_cast<uint32_t>(k));
  const uint32_t phase = static_cast<uint32_t>((frame % k + k) % k);
  if (std::has_single_bit(static_cast<uint32_t>(k))) {
    // For odd log2 k the tile is 2^m x 2^m with each index twice, half a tile diagonal apart:
    // a quincunx, spread better than a 2^m x 2^(m-1) rectangle (k = 2: a checkerboard).
    const int n = std::countr_zero(static_cast<uint32_t>(k)), m = (n + 1) / 2;
    const uint32_t tile_mask = (1u << m) - 1u;
    // The seed shifts the tile and XORs the index: both permute the indices, so each pixel
    // keeps one frame per period and aligned runs of frames stay lattices.
    const uint32_t index = bayer_index(x + (h & tile_mask), y + ((h >> 8) & tile_mask), m) >> (2 * m - n);
    return (index ^ ((h >> 16) & uint32_t(k - 1))) == phase;
  }
  const LatticeSchedule s = lattice_schedule(k);
  return (x + uint64_t{s.c} * y + h) % uint32_t(k) == uint64_t{s.g} * phase % uint32_t(k);
}

}  // namespace

int stratified_period(double spp) {
  const double fraction = spp - std::floor(spp);
  if (!(fraction > 0.0)) return 0;
  const double k = std::round(1.0 / fraction);
  if (k < 2.0 || k > kMaxStratifiedPeriod || std::abs(fraction * k - 1.0) > 1e-6) return 0;
  return static_cast<int>(k);
}

int samples_for_pixel(double spp, uint32_t seed, int frame, uint32_t pixel, int width, SppSchedule schedule) {
  const double whole = std::floor(spp);
  const double fraction = spp - whole;
  int count = static_cast<int>(whole);
  if (!(fraction > 0.0)) return count;
  if (const int period = schedule == SppSchedule::Stratified ? stratified_period(spp) : 0; period > 0) {
    const uint32_t w = static_cast<uint32_t>(std::max(width, 1));
    return count + (stratified_extra_sample(period, seed, frame, pixel % w, pixel / w) ? 1 : 0);
  }
  // Its own hash, not the path's random stream, so the mask does not depend on rendering.
  const uint32_t h = hash_combine(hash_combine(seed ^ 0xA511E9B3u, static_cast<uint32_t>(frame)), pixel);
  if (to_unit_float(h) < fraction) ++count;
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
                                         static_cast<int>(std::ceil(settings.spp)), settings.extra_samples);
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
    TileCorners corners;
    std::vector<Hit> centres;
    const bool footprint = settings.channels.gbuffer && settings.gbuffer_grid > 0;
    for (int t = next_tile++; t < tiles_x * tiles_y; t = next_tile++) {
      const int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
      const int x1 = std::min(x0 + tile, settings.width), y1 = std::min(y0 + tile, settings.height);
      if (footprint) {
        centres.resize(size_t(x1 - x0) * (y1 - y0));
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x)
            centres[size_t(y - y0) * (x1 - x0) + (x - x0)] = scene.intersect(rays.eye(), centre_direction(pc, x, y), ctx);
        build_tile_corners(pc, x0, y0, x1 - x0, y1 - y0, centres, corners, ctx);
      }
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
          render_pixel(pc, x, y, corners, footprint ? &centres[size_t(y - y0) * (x1 - x0) + (x - x0)] : nullptr, fb,
                       ctx);
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
