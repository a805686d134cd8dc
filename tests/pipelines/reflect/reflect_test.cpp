// reflect on the device: its reflection motion pass against the CPU
// reference of the search (reflection_motion_reference.cpp) on path-traced
// frames of dnrender, the static-camera oracle (exactly zero motion), the
// planar-mirror oracle (the mirrored hit's analytic motion), and the whole
// pipeline on the hard cases. Frames: dnrender scene 6 (a planar wall
// mirror and a glossy floor, camera translating) and scene 1 (mirror sphere,
// glossy gold sphere, roughness-mapped coated floor, orbiting camera).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <algorithm>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "camera.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/parameters.hpp"
#include "reflection_motion_reference.hpp"
#include "render.hpp"
#include "scenes.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using namespace svgf_inputs;

class ReflectTest : public test::GpuTest {};

// The channels reflect takes, as dnrender streams them.
const ChannelId kChannels[] = {ChannelId::Diffuse,           ChannelId::Specular,          ChannelId::Emission,
                               ChannelId::Albedo,            ChannelId::SpecularF0,        ChannelId::Roughness,
                               ChannelId::Normal,            ChannelId::Depth,             ChannelId::Motion,
                               ChannelId::Position,          ChannelId::ReflectionPosition, ChannelId::ReflectionAlbedo,
                               ChannelId::ReflectionNormal,  ChannelId::ReflectionDepth,   ChannelId::ReflectionDirection,
                               ChannelId::ReflectionDistance, ChannelId::ReflectionFootprint};

const std::vector<float>& plane(const render::FrameBuffers& fb, ChannelId id) {
  switch (id) {
    case ChannelId::Diffuse: return fb.diffuse;
    case ChannelId::Specular: return fb.specular;
    case ChannelId::Emission: return fb.emission;
    case ChannelId::Albedo: return fb.albedo;
    case ChannelId::SpecularF0: return fb.specular_f0;
    case ChannelId::Roughness: return fb.roughness;
    case ChannelId::Normal: return fb.normal;
    case ChannelId::Depth: return fb.depth;
    case ChannelId::Motion: return fb.motion;
    case ChannelId::Position: return fb.position;
    case ChannelId::ReflectionPosition: return fb.reflection_position;
    case ChannelId::ReflectionAlbedo: return fb.reflection_albedo;
    case ChannelId::ReflectionNormal: return fb.reflection_normal;
    case ChannelId::ReflectionDepth: return fb.reflection_depth;
    case ChannelId::ReflectionDirection: return fb.reflection_direction;
    case ChannelId::ReflectionDistance: return fb.reflection_distance;
    case ChannelId::ReflectionFootprint: return fb.reflection_footprint;
    default: throw std::logic_error("not a reflect channel");
  }
}

pipelines::SessionConfig reflect_config(int w, int h, std::vector<pipelines::ParameterValue> params = {}) {
  std::vector<pipelines::InputChannel> channels;
  for (ChannelId id : kChannels) channels.push_back({id, Format::F32});
  return test::make_config("reflect", w, h, channels, Format::F32, std::move(params));
}

std::array<float, 16> to_array(const glm::mat4& m) {
  std::array<float, 16> a{};
  std::memcpy(a.data(), &m[0][0], sizeof a);
  return a;
}

struct Rendered {
  render::FrameBuffers fb;
  render::Camera camera;
};

// dnrender's settings for a w x h frame with the reflection features.
render::RenderSettings reflection_settings(int w, int h) {
  render::RenderSettings settings;
  settings.width = w;
  settings.height = h;
  settings.channels.reflection = true;
  return settings;
}

// Frame t of a dnrender scene, `stride` path frames apart (more motion per frame).
Rendered render_frame(const render::Scene& scene, int scene_id, int t, int stride, int w, int h) {
  const render::RenderSettings settings = reflection_settings(w, h);
  const render::Camera cam = render::frame_camera(scene_id, stride * t, settings);
  const render::Camera prev = render::frame_camera(scene_id, stride * (t - 1), settings);
  return {render::render_frame(scene, cam, prev, t, settings), cam};
}

test::HostFrame host(const Rendered& r, bool reset) {
  test::HostFrame h;
  h.info.flags = reset ? protocol::kFrameReset : 0u;
  h.info.view = to_array(r.camera.view);
  h.info.projection = to_array(r.camera.projection);
  for (ChannelId id : kChannels) h.add(id, Format::F32, plane(r.fb, id));
  return h;
}

// The reflection classes of docs/protocol.md §7.5 with the pipeline's defaults.
float parameter_default(const char* name) {
  const std::string_view group[] = {"reflect"};
  for (const auto& p : pipelines::parameters_of(group))
    if (p.name == name) return float(p.default_value);
  throw std::logic_error("no such parameter");
}
enum Class { None = 0, Mirror = 1, Glossy = 2 };
Class class_of(const render::FrameBuffers& fb, size_t i) {
  const float r = fb.roughness[i];
  if (!(fb.depth[i] > 0.0f) || !std::isfinite(fb.depth[i]) || !std::isfinite(r)) return None;
  if (r < parameter_default("mirror_roughness")) return Mirror;
  if (r < parameter_default("glossy_roughness")) return Glossy;
  return None;
}

// The reference's fields from a frame's planes (fp32 values, as the device reads them).
struct Fields {
  test::reflect::HitField hits;
  test::reflect::RayField rays;
};
Fields fields_of(const render::FrameBuffers& fb) {
  Fields f;
  const int w = fb.width, h = fb.height;
  const size_t n = size_t(w) * h;
  f.hits.width = f.rays.width = w;
  f.hits.height = f.rays.height = h;
  f.hits.position.resize(n);
  f.hits.valid.assign(n, 0);
  f.rays.origin.resize(n);
  f.rays.direction.resize(n);
  f.rays.depth.assign(n, 0.0);
  f.rays.valid.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const Class c = class_of(fb, i);
    auto at3 = [&](const std::vector<float>& v) { return std::array<double, 3>{v[3 * i], v[3 * i + 1], v[3 * i + 2]}; };
    if (c == Mirror) {
      f.hits.position[i] = at3(fb.reflection_position);
      f.hits.valid[i] = 1;
    } else if (c == Glossy) {
      const float t = fb.reflection_distance[i];
      std::array<double, 3> d = at3(fb.reflection_direction);
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (double& x : d) x = double(float(x / len));  // the device normalises in fp32
      f.rays.origin[i] = at3(fb.position);
      f.rays.direction[i] = d;
      f.rays.depth[i] = t;
      f.rays.valid[i] = t > 0.0f && std::isfinite(t);
    }
  }
  return f;
}

std::vector<float> floats(const std::vector<uint8_t>& bytes) {
  std::vector<float> out(bytes.size() / 4);
  std::memcpy(out.data(), bytes.data(), out.size() * 4);
  return out;
}

// A fresh reflect session with capture on, fed `frames` in order (the first
// as a reset); the captures and `out` are the last frame's.
struct CapturedRun {
  std::unique_ptr<pipelines::Pipeline> pipe;
  pipelines::GraphPipeline* graph = nullptr;
  std::vector<float> out;
  std::vector<float> captured(const std::string& pass, const std::string& buffer) const {
    return floats(graph->captured(pass, buffer));
  }
};
CapturedRun run_captured(gpu::Context& ctx, const std::vector<const Rendered*>& frames,
                         std::vector<pipelines::ParameterValue> params = {}) {
  CapturedRun r;
  r.pipe = pipelines::create(ctx, reflect_config(frames.front()->fb.width, frames.front()->fb.height, std::move(params)));
  r.graph = dynamic_cast<pipelines::GraphPipeline*>(r.pipe.get());
  if (!r.graph) throw std::logic_error("reflect is not a graph pipeline");
  r.graph->set_capture(true);
  for (size_t t = 0; t < frames.size(); ++t) r.out = run(*r.pipe, host(*frames[t], t == 0));
  return r;
}
// Frames first..last of a dnrender scene, `stride` path frames apart.
std::vector<Rendered> render_sequence(int scene_id, int first, int last, int stride, int w, int h) {
  const auto scene = render::build_scene(scene_id);
  std::vector<Rendered> seq;
  for (int t = first; t <= last; ++t) seq.push_back(render_frame(*scene, scene_id, t, stride, w, h));
  return seq;
}
std::vector<const Rendered*> pointers(const std::vector<Rendered>& seq) {
  std::vector<const Rendered*> out;
  for (const auto& r : seq) out.push_back(&r);
  return out;
}

// Runs frames a then b through a fresh reflect session and returns
// reflect_motion's vec4(motion, class, distance) per pixel for frame b.
std::vector<float> reflection_motion(gpu::Context& ctx, const Rendered& a, const Rendered& b) {
  return run_captured(ctx, {&a, &b}).captured("reflect_motion", "reflect_motion");
}
// The same with the virtual point's motion (vec2 per pixel) reflect_prepare wrote for frame b.
struct SearchCapture {
  std::vector<float> motion, virtual_motion;
};
SearchCapture search_capture(gpu::Context& ctx, const Rendered& a, const Rendered& b) {
  const CapturedRun r = run_captured(ctx, {&a, &b});
  return {r.captured("reflect_motion", "reflect_motion"),
          r.captured("reflect_prepare", "reflect_virtual_motion")};
}

struct Agreement {
  int searched = 0, equal = 0, within_1px = 0, class_mismatch = 0;
};

// The device's motion of every mirror and glossy pixel against the CPU
// reference's diamond search and sub-pixel step on the same fields, with
// the device's virtual motion as the third start.
Agreement compare_with_reference(const Rendered& a, const Rendered& b, const SearchCapture& capture) {
  const std::vector<float>& got = capture.motion;
  const Fields prev = fields_of(a.fb), cur = fields_of(b.fb);
  const int w = b.fb.width, h = b.fb.height;
  Agreement out;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const Class c = class_of(b.fb, i);
      if (c == None) continue;
      const std::array<double, 2> mv{b.fb.motion[2 * i], b.fb.motion[2 * i + 1]};
      test::reflect::IntegerMatch m;
      test::reflect::SubpixelMatch s;
      test::reflect::SearchOptions options;
      options.virtual_motion = {capture.virtual_motion[2 * i], capture.virtual_motion[2 * i + 1]};
      if (c == Mirror) {
        m = test::reflect::diamond_search(cur.hits, prev.hits, x, y, mv, options);
        s = test::reflect::refine_subpixel(cur.hits, prev.hits, x, y, m);
      } else {
        if (!cur.rays.valid[i]) continue;
        m = test::reflect::diamond_search(cur.rays, prev.rays, x, y, mv, options);
        s = test::reflect::refine_subpixel(cur.rays, prev.rays, x, y, m);
      }
      if (!std::isfinite(m.distance)) continue;
      ++out.searched;
      if (got[4 * i + 2] != float(c)) ++out.class_mismatch;
      const double dx = got[4 * i] - (s.x - x), dy = got[4 * i + 1] - (s.y - y);
      const double err = std::sqrt(dx * dx + dy * dy);
      if (err < 0.01) ++out.equal;
      if (err < 1.0) ++out.within_1px;
    }
  return out;
}

TEST_F(ReflectTest, MotionSearchMatchesTheCpuReferenceOnRenderedFrames) {
  const int w = 128, h = 72;
  for (int scene_id : {6, 1}) {
    SCOPED_TRACE("scene " + std::to_string(scene_id));
    const auto scene = render::build_scene(scene_id);
    const Rendered a = render_frame(*scene, scene_id, 1, 4, w, h), b = render_frame(*scene, scene_id, 2, 4, w, h);
    const Agreement r = compare_with_reference(a, b, search_capture(ctx(), a, b));
    std::printf("scene %d: %d searched pixels, %.1f %% equal to 0.01 px, %.1f %% within 1 px, %d class mismatches\n",
                scene_id, r.searched, 100.0 * r.equal / r.searched, 100.0 * r.within_1px / r.searched,
                r.class_mismatch);
    ASSERT_GT(r.searched, w * h / 20) << "too few reflective pixels to say anything";
    EXPECT_EQ(r.class_mismatch, 0);
    // fp32 against double: near-ties may take another path; nearly all agree.
    EXPECT_GE(r.equal, 0.97 * r.searched);
    EXPECT_GE(r.within_1px, 0.99 * r.searched);
  }
}

// The thesis's accuracy figure (§7.4, Figs. 12-13; IMPLEMENTATION-NOTES C.4-1)
// on rendered frames: over a moving-camera sequence of scene 6 (planar wall
// mirror, glossy floor) and scene 1 (mirror and glossy spheres), the device's
// reflection motion of every mirror and glossy pixel against the brute-force
// optimum of the same distance (every previous pixel, then the same sub-pixel
// step). Asserted on scene 6, one surface per class as in the thesis's test:
// on average over the frames, > 90 % within 1 px ("on average more than 90 %
// of the found motion vectors in a frame are within one pixel of the
// optimum"). Scene 1 is measured, not asserted: its mirror class holds the
// sphere and the floor's smooth stripes, its glossy class two spheres, so
// the global optimum may lie on another object (and it measured 83 % and 77 %,
// 86 % and 79 % with brute force limited to +-20 px: local minima too).
// DN_MOTION_ACCURACY_OUT=FILE writes the per-frame figures
// (bench/reflection_motion.sh plots them).
TEST_F(ReflectTest, MotionAccuracyAgainstBruteForceOverAFlythrough) {
  const int w = 96, h = 54, frames = 6;
  FILE* tsv = nullptr;
  if (const char* path = std::getenv("DN_MOTION_ACCURACY_OUT")) {
    tsv = std::fopen(path, "w");
    ASSERT_NE(tsv, nullptr) << path;
    std::fprintf(tsv, "scene\tframe\tclass\tpixels\twithin_1px\tmean_error_px\n");
  }
  for (int scene_id : {6, 1}) {
    SCOPED_TRACE("scene " + std::to_string(scene_id));
    const std::vector<Rendered> seq = render_sequence(scene_id, 1, frames, 2, w, h);
    auto pipe = pipelines::create(ctx(), reflect_config(w, h));
    auto* graph = dynamic_cast<pipelines::GraphPipeline*>(pipe.get());
    ASSERT_NE(graph, nullptr);
    graph->set_capture(true);
    double share_sum[3] = {0, 0, 0};
    int share_frames[3] = {0, 0, 0};
    for (int t = 0; t < frames; ++t) {
      run(*pipe, host(seq[size_t(t)], t == 0));
      if (t == 0) continue;
      const std::vector<float> got = floats(graph->captured("reflect_motion", "reflect_motion"));
      const Fields prev = fields_of(seq[size_t(t) - 1].fb), cur = fields_of(seq[size_t(t)].fb);
      int pixels[3] = {0, 0, 0}, within[3] = {0, 0, 0};
      double error[3] = {0, 0, 0};
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const size_t i = size_t(y) * w + x;
          const Class c = class_of(seq[size_t(t)].fb, i);
          if (c == None || got[4 * i + 3] < 0.0f) continue;
          test::reflect::SubpixelMatch best;
          if (c == Mirror) {
            const auto m = test::reflect::brute_force_search(cur.hits, prev.hits, x, y, 100);
            if (!std::isfinite(m.distance)) continue;
            best = test::reflect::refine_subpixel(cur.hits, prev.hits, x, y, m);
          } else {
            if (!cur.rays.valid[i]) continue;
            const auto m = test::reflect::brute_force_search(cur.rays, prev.rays, x, y, 100);
            if (!std::isfinite(m.distance)) continue;
            best = test::reflect::refine_subpixel(cur.rays, prev.rays, x, y, m);
          }
          const double e = std::hypot(got[4 * i] - (best.x - x), got[4 * i + 1] - (best.y - y));
          ++pixels[c];
          within[c] += e <= 1.0;
          error[c] += e;
        }
      for (int c : {int(Mirror), int(Glossy)}) {
        if (pixels[c] == 0) continue;
        share_sum[c] += double(within[c]) / pixels[c];
        share_frames[c]++;
        if (tsv)
          std::fprintf(tsv, "%d\t%d\t%s\t%d\t%.4f\t%.4f\n", scene_id, t, c == Mirror ? "mirror" : "glossy", pixels[c],
                       double(within[c]) / pixels[c], error[c] / pixels[c]);
      }
    }
    for (int c : {int(Mirror), int(Glossy)}) {
      ASSERT_GT(share_frames[c], 0) << (c == Mirror ? "no mirror pixel" : "no glossy pixel");
      const double mean = share_sum[c] / share_frames[c];
      std::printf("[ info     ] scene %d %s: %.1f %% within 1 px of brute force (mean over %d frames)\n", scene_id,
                  c == Mirror ? "mirror" : "glossy", 100.0 * mean, share_frames[c]);
      if (scene_id == 6) {
        EXPECT_GT(mean, 0.9) << (c == Mirror ? "mirror" : "glossy");
      }
    }
  }
  if (tsv) std::fclose(tsv);
}

TEST_F(ReflectTest, StaticCameraGivesExactlyZeroReflectionMotion) {
  const int w = 96, h = 54, scene_id = 1;
  const auto scene = render::build_scene(scene_id);
  const Rendered a = render_frame(*scene, scene_id, 3, 0, w, h);  // stride 0: the same camera twice
  const std::vector<float> got = reflection_motion(ctx(), a, a);
  int reflective = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    if (got[4 * i + 3] < 0.0f) continue;  // no match (class none, or no ray)
    ++reflective;
    ASSERT_EQ(got[4 * i], 0.0f) << "pixel " << i;
    ASSERT_EQ(got[4 * i + 1], 0.0f) << "pixel " << i;
  }
  EXPECT_GT(reflective, w * h / 10);
}

// Scene 6's wall mirror is planar and the scene static: what a mirror pixel
// shows is the mirror image of a point, fixed in the world, seen through the
// mirror, so its motion is the virtual point's (the camera ray extended by
// the chain's length) projected with the previous camera (NRD's virtual
// motion; IMPLEMENTATION-NOTES C.4-3).
TEST_F(ReflectTest, PlanarMirrorAgreesWithTheAnalyticMotion) {
  const int w = 128, h = 72, scene_id = 6;
  const auto scene = render::build_scene(scene_id);
  const Rendered a = render_frame(*scene, scene_id, 1, 4, w, h), b = render_frame(*scene, scene_id, 2, 4, w, h);
  const std::vector<float> got = reflection_motion(ctx(), a, b);
  const glm::mat4 prev_vp = a.camera.projection * a.camera.view;
  const glm::vec3 eye = glm::vec3(glm::inverse(b.camera.view)[3]);
  int mirrors = 0, within = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (got[4 * i + 2] != float(Mirror) || got[4 * i + 3] < 0.0f || !(b.fb.reflection_depth[i] > 0.0f)) continue;
      const glm::vec3 primary(b.fb.position[3 * i], b.fb.position[3 * i + 1], b.fb.position[3 * i + 2]);
      const glm::vec3 hit(b.fb.reflection_position[3 * i], b.fb.reflection_position[3 * i + 1],
                          b.fb.reflection_position[3 * i + 2]);
      const float t1 = glm::length(primary - eye), t2 = glm::length(hit - primary);
      const glm::vec3 virtual_point = eye + glm::normalize(primary - eye) * (t1 + t2);
      const glm::vec2 prev = render::project_to_pixel(prev_vp, virtual_point, w, h);
      const glm::vec2 analytic = prev - glm::vec2(x + 0.5f, y + 0.5f);
      ++mirrors;
      if (glm::length(analytic - glm::vec2(got[4 * i], got[4 * i + 1])) <= 1.0f) ++within;
    }
  std::printf("planar mirror: %d mirror pixels, %.1f %% within 1 px of the analytic motion\n", mirrors,
              100.0 * within / std::max(mirrors, 1));
  ASSERT_GT(mirrors, w * h / 10);
  EXPECT_GE(within, 0.9 * mirrors);
}

// The search's third start (reflect.virtual_start; docs/pipelines.md
// "reflect"): reflect_prepare's virtual motion is the virtual point, the
// camera ray extended by the reflection's length (at a mirror the whole
// chain's, unfolded by the virtual depth; at a glossy pixel the
// representative ray's hit distance), projected with the previous camera,
// computed here in double from the frame's planes and cameras. 1e30 (no
// start) at every other pixel.
TEST_F(ReflectTest, VirtualMotionIsTheVirtualPointsProjection) {
  const int w = 96, h = 54;
  for (int scene_id : {6, 1}) {
    SCOPED_TRACE("scene " + std::to_string(scene_id));
    const std::vector<Rendered> seq = render_sequence(scene_id, 1, 2, 4, w, h);
    const Rendered &a = seq[0], &b = seq[1];
    const std::vector<float> got = search_capture(ctx(), a, b).virtual_motion;
    const glm::dmat4 prev_vp = glm::dmat4(a.camera.projection) * glm::dmat4(a.camera.view);
    const glm::dvec3 eye = glm::dvec3(glm::inverse(glm::dmat4(b.camera.view))[3]);
    int checked[3] = {0, 0, 0};
    double worst = 0.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const Class c = class_of(b.fb, i);
        const glm::dvec3 o(b.fb.position[3 * i], b.fb.position[3 * i + 1], b.fb.position[3 * i + 2]);
        glm::dvec3 virtual_point;
        bool exists = false;
        if (c == Mirror && b.fb.reflection_depth[i] > 0.0f && std::isfinite(b.fb.reflection_depth[i])) {
          virtual_point = eye + (o - eye) * (double(b.fb.reflection_depth[i]) / b.fb.depth[i]);
          exists = true;
        } else if (c == Glossy && b.fb.reflection_distance[i] > 0.0f && std::isfinite(b.fb.reflection_distance[i])) {
          virtual_point = o + glm::normalize(o - eye) * double(b.fb.reflection_distance[i]);
          exists = true;
        }
        const glm::dvec4 clip = prev_vp * glm::dvec4(virtual_point, 1.0);
        if (!exists || !(clip.w > 0.0)) {
          ASSERT_EQ(got[2 * i], 1e30f) << "pixel " << i;
          continue;
        }
        const double px = (clip.x / clip.w * 0.5 + 0.5) * w - (x + 0.5);
        const double py = (0.5 - clip.y / clip.w * 0.5) * h - (y + 0.5);
        const double e = std::hypot(got[2 * i] - px, got[2 * i + 1] - py);
        worst = std::max(worst, e);
        ASSERT_LE(e, 0.01) << "pixel (" << x << ", " << y << ")";
        ++checked[c];
      }
    std::printf("[ info     ] scene %d: %d mirror and %d glossy virtual motions, worst %.2g px\n", scene_id,
                checked[Mirror], checked[Glossy], worst);
    EXPECT_GT(checked[Mirror], w * h / 40);
    EXPECT_GT(checked[Glossy], w * h / 40);
  }
}

// The Eq. 1 threshold (reflect.mirror_match_threshold): a mirror pixel's
// match is rejected exactly when its hit distance exceeds the threshold
// times the spacing of the previous frame's hits at the match (the smallest
// distance to an axis neighbour's mirror hit), decided here from the CPU
// reference's search; a rejected pixel's specular history restarts (length
// 1), and glossy pixels are never rejected.
TEST_F(ReflectTest, MirrorMatchThresholdRejectsDistantMatches) {
  const int w = 96, h = 54;
  const double threshold = 0.5;
  for (int scene_id : {6, 1}) {
    SCOPED_TRACE("scene " + std::to_string(scene_id));
    const std::vector<Rendered> seq = render_sequence(scene_id, 1, 3, 4, w, h);
    const Rendered &a = seq[1], &b = seq[2];
    const CapturedRun run = run_captured(ctx(), pointers(seq), {{"mirror_match_threshold", threshold}});
    const std::vector<float> got = run.captured("reflect_motion", "reflect_motion");
    const std::vector<float> vm = run.captured("reflect_prepare", "reflect_virtual_motion");
    const std::vector<float> temporal = run.captured("svgf_reproject_specular", "svgf_temporal_specular");
    const Fields prev = fields_of(a.fb), cur = fields_of(b.fb);
    int kept = 0, rejected = 0, disagree = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const Class c = class_of(b.fb, i);
        if (c == Glossy) {
          ASSERT_NE(got[4 * i + 3], -2.0f) << "glossy pixel " << i;
        }
        if (c != Mirror) continue;
        test::reflect::SearchOptions options;
        options.virtual_motion = {vm[2 * i], vm[2 * i + 1]};
        const auto m = test::reflect::diamond_search(cur.hits, prev.hits, x, y,
                                                     {b.fb.motion[2 * i], b.fb.motion[2 * i + 1]}, options);
        if (!std::isfinite(m.distance)) continue;
        double spacing = std::numeric_limits<double>::infinity();
        for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const int qx = m.x + dx, qy = m.y + dy;
          if (!prev.hits.inside(qx, qy) || !prev.hits.valid[prev.hits.index(qx, qy)]) continue;
          const auto& p0 = prev.hits.position[prev.hits.index(m.x, m.y)];
          const auto& p1 = prev.hits.position[prev.hits.index(qx, qy)];
          spacing = std::min(spacing, std::hypot(p0[0] - p1[0], p0[1] - p1[1], p0[2] - p1[2]));
        }
        // Near-ties of fp32 against double decide nothing here.
        if (std::isfinite(spacing) && std::fabs(m.distance - threshold * spacing) < 1e-4 * spacing) continue;
        const bool want = std::isfinite(spacing) && m.distance > threshold * spacing;
        const bool is = got[4 * i + 3] == -2.0f;
        if (want != is) ++disagree;
        if (is) {
          ++rejected;
          EXPECT_EQ(temporal[4 * i + 2], 1.0f) << "a rejected pixel's history restarts, pixel " << i;
        } else {
          ++kept;
        }
      }
    std::printf("[ info     ] scene %d: %d mirror matches kept, %d rejected at threshold %.1f\n", scene_id, kept,
                rejected, threshold);
    EXPECT_EQ(disagree, 0);
    EXPECT_GT(rejected, 0);
    EXPECT_GT(kept, 0);
  }
}

// Hard cases (docs/pipelines.md "reflect"): bad reflection features (NaN and
// infinite hits, zero and NaN directions, NaN and negative distances, NaN
// roughness, zero and NaN reflected albedo) and bad radiance at some pixels
// never reach the output or the history: every output value of the bad frame
// and of the good frame after it is finite and >= 0.
TEST_F(ReflectTest, BadFeaturesNeverReachTheOutput) {
  const int w = 64, h = 36, scene_id = 1;
  const auto scene = render::build_scene(scene_id);
  std::vector<Rendered> seq;
  for (int t = 1; t <= 3; ++t) seq.push_back(render_frame(*scene, scene_id, t, 2, w, h));
  Rendered bad = seq[1];
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const size_t n = size_t(w) * h;
  for (size_t i = 0; i < n; i += 7) {
    const int k = int(i / 7) % 7;
    auto& f = bad.fb;
    switch (k) {
      case 0: f.reflection_position[3 * i] = nan; break;
      case 1: f.reflection_position[3 * i + 1] = inf; break;
      case 2: f.reflection_direction[3 * i] = f.reflection_direction[3 * i + 1] = f.reflection_direction[3 * i + 2] = 0.0f; break;
      case 3: f.reflection_distance[i] = (i % 2) ? nan : -1.0f; break;
      case 4: f.roughness[i] = nan; break;
      case 5: f.reflection_albedo[3 * i] = (i % 2) ? nan : 0.0f; break;
      case 6: f.specular[3 * i] = (i % 2) ? inf : nan; break;
    }
  }
  auto pipe = pipelines::create(ctx(), reflect_config(w, h));
  for (int t = 0; t < 3; ++t) {
    const auto out = run(*pipe, host(t == 1 ? bad : seq[size_t(t)], t == 0));
    for (float v : out) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << "frame " << t << ": " << v;
  }
}

// reflect(k x) = k reflect(x) for radiance scaled by k (features unchanged),
// on scene 1 (spheres) and scene 6 (planar mirror, glossy floor).
TEST_F(ReflectTest, OutputScalesWithInput) {
  const int w = 64, h = 36;
  for (int scene_id : {1, 6}) {
    const auto scene = render::build_scene(scene_id);
    std::vector<Rendered> seq;
    for (int t = 1; t <= 4; ++t) seq.push_back(render_frame(*scene, scene_id, t, 4, w, h));
    std::vector<std::vector<float>> base;
    {
      auto pipe = pipelines::create(ctx(), reflect_config(w, h));
      for (int t = 0; t < 4; ++t) base.push_back(run(*pipe, host(seq[size_t(t)], t == 0)));
    }
    for (double k : {1e-6, 1e-3, 1e3, 1e4}) {
      auto pipe = pipelines::create(ctx(), reflect_config(w, h));
      double worst = 0.0;
      for (int t = 0; t < 4; ++t) {
        Rendered r = seq[size_t(t)];
        for (auto* v : {&r.fb.diffuse, &r.fb.specular, &r.fb.emission})
          for (auto& x : *v) x = static_cast<float>(x * k);
        const auto out = run(*pipe, host(r, t == 0));
        std::vector<float> got(out.size());
        std::vector<double> want(out.size());
        for (size_t i = 0; i < out.size(); ++i) {
          got[i] = static_cast<float>(out[i] / k);
          want[i] = base[size_t(t)][i];
        }
        worst = std::max(worst, test::relative_rms(got, want));
      }
      std::printf("[ info     ] reflect scene %d, k = %g: worst relative RMS %.2g\n", scene_id, k, worst);
      EXPECT_LE(worst, 1e-3) << "scene " << scene_id << ", k = " << k;
    }
  }
}

// History clipping (paper 001 §4.2.3, IMPLEMENTATION-NOTES C.4-10): after the
// specular reprojection every pixel with roughness < clip_roughness holds a
// temporal colour inside its clip box, recomputed here from the captured
// prefilter output (the 5x5 box of the 7x7-Gaussian current signal), the
// raw 3x3 range of the current demodulated signal and the pixel's own value
// (docs/pipelines.md "svgf in detail"), with the reflection motion moving
// the history.
TEST_F(ReflectTest, ClippedHistoryStaysInsideItsNeighbourhoodBox) {
  const int w = 96, h = 54;
  const std::vector<Rendered> seq = render_sequence(6, 1, 4, 4, w, h);
  const Rendered& r = seq.back();
  const CapturedRun session = run_captured(ctx(), pointers(seq));
  const std::vector<float> box = session.captured("svgf_clip_prefilter_y_specular", "svgf_clip_neighbourhood");
  const std::vector<float> mod = session.captured("reflect_prepare", "reflect_modulator");
  const std::vector<float> out = session.captured("svgf_reproject_specular", "svgf_illum_c");
  // The current demodulated specular signal, as svgf_signal.glsl computes it.
  auto guard = [](float a) { return std::isfinite(a) && a >= 1e-3f ? a : 1.0f; };
  auto current = [&](int x, int y, int c) {
    const size_t i = size_t(y) * w + x;
    float v = r.fb.specular[3 * i + c];
    if (!std::isfinite(v) || v < 0.0f || v > 1e12f) v = 0.0f;
    return v / guard(mod[3 * i + c]);
  };
  const float clip_roughness = 0.9f;  // svgf's clip_roughness default
  int checked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!(r.fb.depth[i] > 0.0f) || !(r.fb.roughness[i] < clip_roughness)) continue;
      for (int c = 0; c < 3; ++c) {
        const float d = current(x, y, c);
        float pre_lo = 1e38f, pre_hi = -1e38f, raw_lo = d, raw_hi = d;
        for (int yy = -2; yy <= 2; ++yy)
          for (int xx = -2; xx <= 2; ++xx) {
            const int qx = x + xx, qy = y + yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
            const size_t q = size_t(qy) * w + qx;
            if (box[4 * q + 3] != 0.0f) {
              pre_lo = std::min(pre_lo, box[4 * q + c]);
              pre_hi = std::max(pre_hi, box[4 * q + c]);
            }
            if (std::abs(xx) <= 1 && std::abs(yy) <= 1) {
              raw_lo = std::min(raw_lo, current(qx, qy, c));
              raw_hi = std::max(raw_hi, current(qx, qy, c));
            }
          }
        const float nlo = std::max(pre_lo, raw_lo), nhi = std::min(pre_hi, raw_hi);
        const bool overlap = nlo <= nhi;
        const float lo = std::min(overlap ? nlo : raw_lo, d), hi = std::max(overlap ? nhi : raw_hi, d);
        const float v = out[4 * i + c], slack = 1e-5f * std::max(std::abs(lo), std::abs(hi));
        ASSERT_GE(v, lo - slack) << "pixel (" << x << ", " << y << ") channel " << c;
        ASSERT_LE(v, hi + slack) << "pixel (" << x << ", " << y << ") channel " << c;
      }
      ++checked;
    }
  EXPECT_GT(checked, w * h / 4);
}

// specular_history 0 (the NoSpecReproj baseline) reads no specular history:
// its specular temporal colour is the current frame's signal exactly, while
// the default accumulates.
TEST_F(ReflectTest, WithoutSpecularHistoryTheSpecularSignalIsTheCurrentFrame) {
  const int w = 64, h = 36;
  const std::vector<Rendered> seq = render_sequence(6, 1, 3, 4, w, h);
  const Rendered& r = seq.back();
  for (double history : {0.0, 1.0}) {
    const CapturedRun session = run_captured(ctx(), pointers(seq), {{"specular_history", history}});
    const std::vector<float> mod = session.captured("reflect_prepare", "reflect_modulator");
    const std::vector<float> out = session.captured("svgf_reproject_specular", "svgf_illum_c");
    const std::vector<float> temporal = session.captured("svgf_reproject_specular", "svgf_temporal_specular");
    int foreground = 0, fresh = 0;
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      if (!(r.fb.depth[i] > 0.0f)) continue;
      ++foreground;
      const float m = std::isfinite(mod[3 * i]) && mod[3 * i] >= 1e-3f ? mod[3 * i] : 1.0f;
      if (temporal[4 * i + 2] == 1.0f && out[4 * i] == r.fb.specular[3 * i] / m) ++fresh;  // length 1, current value
    }
    if (history == 0.0)
      EXPECT_EQ(fresh, foreground);
    else
      EXPECT_LT(fresh, foreground / 2) << "the default keeps specular history";
  }
}

// The firefly median (paper 001 §6; IMPLEMENTATION-NOTES C.4-9): with it the
// output at a foreground pixel whose foreground 3x3 window is all of
// reflection class none, and whose light (colour minus emission) is
// brighter in luminance than the window's median, is, per channel, the value
// of rank count / 2 among the window's colours minus emission in the output
// without it (emitting neighbours left out), plus the pixel's emission;
// elsewhere the same; every history buffer is bit-identical with the median
// on or off. (A moving camera: no pixel is still long enough to keep its own.)
// With TAA (the default) svgf_taa writes the displayed frame the median
// reads; without it svgf_remodulate does (both TO_DISPLAY).
class ReflectMedianTest : public ReflectTest, public testing::WithParamInterface<bool> {};

TEST_P(ReflectMedianTest, FireflyMedianChangesTheDisplayedFrameOnly) {
  const int w = 64, h = 36;
  const std::vector<Rendered> seq = render_sequence(1, 1, 4, 2, w, h);
  const bool taa = GetParam();
  struct Run {
    std::vector<float> out, features;
    std::map<std::string, std::vector<uint8_t>> history;
  };
  auto run_with = [&](double median) {
    std::vector<pipelines::ParameterValue> params = {{"firefly_median", median}};
    if (!taa) params.push_back({"taa_static_alpha", 0.0});
    const CapturedRun captured = run_captured(ctx(), pointers(seq), params);
    const pipelines::GraphPipeline* graph = captured.graph;
    Run r;
    r.out = captured.out;
    r.features = captured.captured("reflect_prepare", "reflect_features");
    // Each persistent or history buffer as the last pass that binds it left it.
    for (const auto& b : graph->spec().buffers) {
      if (b.role != pipelines::BufferRole::Persistent && b.role != pipelines::BufferRole::History) continue;
      std::string last;
      for (const auto& pass : graph->spec().passes)
        for (const auto& ref : pass.bindings())
          if (ref.buffer == b.name) last = pass.name();
      r.history[b.name] = graph->captured(last, b.name);
    }
    return r;
  };
  const Run off = run_with(0.0), on = run_with(1.0);
  ASSERT_FALSE(off.history.empty());
  for (const auto& [name, bytes] : off.history) EXPECT_EQ(bytes, on.history.at(name)) << name;
  const auto& depth = seq.back().fb.depth;
  const auto& emission = seq.back().fb.emission;
  int filtered = 0, changed = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      auto fg = [&](size_t q) { return depth[q] > 0.0f && std::isfinite(depth[q]); };
      auto emits = [&](size_t q) {
        return 0.2126f * emission[3 * q] + 0.7152f * emission[3 * q + 1] + 0.0722f * emission[3 * q + 2] > 0.0f;
      };
      auto filtered_light = [&](size_t q) {  // the output without emission, as the pass computes it in fp32
        return std::array<float, 3>{off.out[3 * q] - emission[3 * q], off.out[3 * q + 1] - emission[3 * q + 1],
                                    off.out[3 * q + 2] - emission[3 * q + 2]};
      };
      std::array<float, 3> want{off.out[3 * i], off.out[3 * i + 1], off.out[3 * i + 2]};
      std::vector<size_t> window;
      bool all_none = off.features[8 * i + 3] == 0.0f && fg(i);
      for (int yy = -1; yy <= 1 && all_none; ++yy)
        for (int xx = -1; xx <= 1; ++xx) {
          const int qx = x + xx, qy = y + yy;
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
          const size_t q = size_t(qy) * w + qx;
          if (!fg(q)) continue;
          if (off.features[8 * q + 3] != 0.0f) all_none = false;
          if (q != i && emits(q)) continue;  // a light is another surface
          window.push_back(q);
        }
      if (all_none) {
        std::array<float, 3> median{};
        for (int c = 0; c < 3; ++c) {
          std::vector<float> values;
          for (size_t q : window) values.push_back(filtered_light(q)[size_t(c)]);
          std::sort(values.begin(), values.end());
          median[size_t(c)] = values[values.size() / 2];
        }
        auto luminance = [](const std::array<float, 3>& v) { return 0.2126f * v[0] + 0.7152f * v[1] + 0.0722f * v[2]; };
        const float own = luminance(filtered_light(i)), mid = luminance(median);
        if (std::fabs(own - mid) <= 1e-5f * std::max(std::fabs(own), std::fabs(mid))) continue;  // a tie: either
        if (own > mid) {
          for (int c = 0; c < 3; ++c) want[size_t(c)] = median[size_t(c)] + emission[3 * i + c];
          ++filtered;
        }
      }
      for (int c = 0; c < 3; ++c) ASSERT_EQ(on.out[3 * i + c], want[size_t(c)]) << "pixel (" << x << ", " << y << ")";
      changed += on.out[3 * i] != off.out[3 * i];
    }
  EXPECT_GT(filtered, w * h / 10);
  EXPECT_GT(changed, 0);
}

INSTANTIATE_TEST_SUITE_P(Taa, ReflectMedianTest, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& info) { return info.param ? "with_taa" : "without_taa"; });

// A still view converges (dnrender scene 3, 128x72, 1 spp, the camera held):
// after 8 and after 24 frames the output is nearer the converged image (the
// mean of 256 frames of another seed) than the plain running mean of its
// inputs, by RMSE. The firefly median once took the lit surface one pixel
// wide beside the lamp for fireflies, against the lamp's near-zero
// reflected light, on every frame: RMSE 3x the running mean's after 64.
TEST_F(ReflectTest, AStillViewIsNearerTheReferenceThanTheRunningMean) {
  const int w = 128, h = 72, scene_id = 3;
  const auto scene = render::build_scene(scene_id);
  const render::RenderSettings settings = reflection_settings(w, h);
  const render::Camera cam = render::frame_camera(scene_id, 0, settings);
  const size_t n = size_t(w) * h * 3;
  std::vector<double> reference(n, 0.0);
  render::RenderSettings other = settings;
  other.seed = 7;
  const int reference_frames = 256;
  for (int t = 0; t < reference_frames; ++t) {
    const render::FrameBuffers fb = render::render_frame(*scene, cam, cam, t, other);
    for (size_t i = 0; i < n; ++i) reference[i] += fb.radiance[i] / reference_frames;
  }
  auto rmse = [&](auto&& value) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += (value(i) - reference[i]) * (value(i) - reference[i]);
    return std::sqrt(sum / double(n));
  };
  auto pipe = pipelines::create(ctx(), reflect_config(w, h));
  std::vector<double> mean(n, 0.0);
  for (int t = 0; t < 24; ++t) {
    const Rendered r{render::render_frame(*scene, cam, cam, t, settings), cam};
    for (size_t i = 0; i < n; ++i) mean[i] += (r.fb.radiance[i] - mean[i]) / (t + 1);
    const std::vector<float> out = run(*pipe, host(r, t == 0));
    if (t + 1 != 8 && t + 1 != 24) continue;
    const double denoised = rmse([&](size_t i) { return double(out[i]); });
    const double plain = rmse([&](size_t i) { return mean[i]; });
    EXPECT_LT(denoised, plain) << "after " << t + 1 << " frames";
  }
}


// Still frames of dnrender scene 6 at 96x54, frame t changed by
// change(fb, t), through reflect with `params`: how many pixels of the last
// frame `counts` picks (by class and reflect_motion's vec4), and how many of
// those hold every frame's sample in their specular still mean.
struct StillMeansKept {
  int counted = 0, whole = 0;
};
StillMeansKept still_means_kept(gpu::Context& context, int frames,
                                const std::function<void(render::FrameBuffers&, int)>& change,
                                std::vector<pipelines::ParameterValue> params,
                                const std::function<bool(Class, const float*)>& counts) {
  const int w = 96, h = 54, scene_id = 6;
  const auto scene = render::build_scene(scene_id);
  const render::RenderSettings settings = reflection_settings(w, h);
  const render::Camera cam = render::frame_camera(scene_id, 0, settings);
  std::vector<Rendered> seq;
  for (int t = 0; t < frames; ++t) {
    Rendered r{render::render_frame(*scene, cam, cam, t, settings), cam};
    change(r.fb, t);
    seq.push_back(std::move(r));
  }
  const CapturedRun run = run_captured(context, pointers(seq), std::move(params));
  const std::vector<float> motion = run.captured("reflect_motion", "reflect_motion");
  const std::vector<float> still = run.captured("svgf_reproject_specular", "svgf_spec_still");
  StillMeansKept kept;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    if (!counts(class_of(seq.back().fb, i), &motion[4 * i])) continue;
    ++kept.counted;
    kept.whole += still[4 * i + 3] == float(frames);
  }
  return kept;
}

// A still mirror whose reflection match Eq. 1 rejects (at 1 spp a renderer's
// reflected hit moves with each sample's position in the pixel: here every
// mirror hit is shifted 0.05 along x, alternately each frame, against a
// threshold of 0.001) restarts its specular history but keeps its still
// mean, which follows the pixel's own surface (the diffuse chain's still
// mean), not the reflected hit: the pixel and camera have not moved, so
// every frame's sample is one more of the same mean (its change test
// catches a change of light). After 6 frames of dnrender scene 6 every such
// pixel's specular still mean holds all 6 samples.
TEST_F(ReflectTest, AStillMirrorKeepsItsMeanWhenItsMatchIsRejected) {
  const int frames = 6;
  auto shift = [](render::FrameBuffers& fb, int t) {
    for (size_t i = 0; i < fb.reflection_depth.size(); ++i)
      if (class_of(fb, i) == Mirror) fb.reflection_position[3 * i] += t % 2 ? 0.05f : -0.05f;
  };
  auto rejected = [](Class c, const float* motion) { return c == Mirror && motion[3] == -2.0f; };
  const StillMeansKept kept = still_means_kept(ctx(), frames, shift, {{"mirror_match_threshold", 0.001}}, rejected);
  std::printf("[ info     ] %d still mirror pixels rejected by Eq. 1; %d keep all %d samples in their still mean\n",
              kept.counted, kept.whole, frames);
  EXPECT_GT(kept.counted, 96 * 54 / 40);
  EXPECT_EQ(kept.whole, kept.counted);
}

// A still glossy pixel's representative-ray match (Eq. 4-5) follows each
// sample's reflected hit, which at 1 spp changes with every sample (Cycles'
// Denoising Depth ends some samples' chains before the glossy hit: no ray).
// Here the glossy pixels of every other column have no ray in the odd
// frames, so in the even ones their match lands beside them, and the other
// columns' on them in the odd ones. The pixel and camera have not moved, so
// its still mean goes on: after 7 frames of dnrender scene 6 every glossy
// pixel whose match moved keeps all 7 samples in its specular still mean
// (its stillness is its surface's motion; a mirror's is its reflection's).
TEST_F(ReflectTest, AStillGlossyPixelKeepsItsMeanWhenItsRayMatchMoves) {
  const int frames = 7;
  auto drop_rays = [](render::FrameBuffers& fb, int t) {
    for (size_t i = 0; i < fb.reflection_distance.size(); ++i)
      if (class_of(fb, i) == Glossy && t % 2 == 1 && i % 2 == 0) fb.reflection_distance[i] = 0.0f;
  };
  auto moved = [](Class c, const float* motion) { return c == Glossy && std::hypot(motion[0], motion[1]) >= 0.005; };
  const StillMeansKept kept = still_means_kept(ctx(), frames, drop_rays, {}, moved);
  std::printf("[ info     ] %d still glossy pixels whose ray match moved; %d keep all %d samples in their still mean\n",
              kept.counted, kept.whole, frames);
  EXPECT_GT(kept.counted, 96 * 54 / 40);
  EXPECT_EQ(kept.whole, kept.counted);
}

// A pass's buffer bound at `binding` (1-based: the n-th row of its .pass file).
std::string bound(const pipelines::GraphPipeline& graph, const std::string& pass, size_t binding) {
  for (const auto& p : graph.spec().passes)
    if (p.name() == pass) return p.bindings().at(binding - 1).buffer;
  throw std::logic_error("no pass " + pass);
}

// Eq. 6 (paper 001; docs/pipelines.md "reflect"): reflect_prepare writes
// sigma = max(exp(-footprint / omega), 0.05) at glossy pixels and 0
// elsewhere; the specular a-trous weights its taps by
// exp(-|(i, j)|^2 / (2 sigma^2)), so at the floor (omega tiny) a glossy
// pixel's taps weigh exp(-200), 0 in fp32, and its first iteration returns
// its input exactly, while every other pixel's first iteration is the one
// without Eq. 6, bit for bit (one reset frame: same inputs).
TEST_F(ReflectTest, FootprintBandwidthNarrowsOnlyGlossyPixels) {
  const int w = 64, h = 36;
  const std::vector<Rendered> seq = render_sequence(1, 2, 2, 1, w, h);
  const Rendered& r = seq.front();
  const std::string atrous = "svgf_atrous_0";  // the joint pass: specular is its second signal (src2, dst2)
  {
    const double omega = 0.5;
    const CapturedRun on = run_captured(ctx(), pointers(seq), {{"footprint_omega", omega}});
    const std::vector<float> sigma = on.captured("reflect_prepare", "reflect_bandwidth");
    const std::vector<float> features = on.captured("reflect_prepare", "reflect_features");
    int glossy = 0;
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      const float fp = r.fb.reflection_footprint[i];
      if (features[8 * i + 3] == float(Glossy)) {
        ++glossy;
        const double want = std::max(std::exp(-fp / omega), 0.05);
        ASSERT_NEAR(sigma[i], want, 1e-6 * want) << "pixel " << i;
      } else {
        ASSERT_EQ(sigma[i], 0.0f) << "pixel " << i;
      }
    }
    EXPECT_GT(glossy, w * h / 20);
  }
  const CapturedRun off = run_captured(ctx(), pointers(seq));
  const CapturedRun floor = run_captured(ctx(), pointers(seq), {{"footprint_omega", 1e-4}});
  const std::string src = bound(*floor.graph, atrous, 8), dst = bound(*floor.graph, atrous, 9);
  ASSERT_EQ(src, bound(*off.graph, atrous, 8));
  const std::vector<float> in = floor.captured(atrous, src), got = floor.captured(atrous, dst);
  const std::vector<float> without = off.captured(atrous, dst);
  const std::vector<float> features = floor.captured("reflect_prepare", "reflect_features");
  int glossy = 0, other = 0, changed = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    const bool is_glossy = features[8 * i + 3] == float(Glossy);
    for (int c = 0; c < 3; ++c) {
      if (is_glossy)
        ASSERT_EQ(got[4 * i + c], in[4 * i + c]) << "glossy pixel " << i;
      else
        ASSERT_EQ(got[4 * i + c], without[4 * i + c]) << "pixel " << i;
    }
    if (is_glossy) {
      ++glossy;
      if (without[4 * i] != in[4 * i]) ++changed;
    } else if (r.fb.depth[i] > 0.0f) {
      ++other;
    }
  }
  EXPECT_GT(other, w * h / 4);
  EXPECT_GT(changed, glossy / 2) << "without Eq. 6 the glossy pixels are filtered";
}

}  // namespace
}  // namespace dn
