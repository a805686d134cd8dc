#include "scene.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <limits>
#include <thread>

namespace dn::synth {
namespace {

struct Sphere {
  glm::vec3 centre;
  float radius;
  glm::vec3 albedo;
};

const Sphere kSpheres[] = {
    {{-1.2f, 0.6f, 0.0f}, 0.6f, {0.80f, 0.25f, 0.20f}},
    {{0.3f, 0.45f, -0.8f}, 0.45f, {0.20f, 0.60f, 0.85f}},
    {{1.4f, 0.8f, 0.6f}, 0.8f, {0.85f, 0.85f, 0.80f}},
};
const glm::vec3 kSunDirection = glm::normalize(glm::vec3(0.5f, 1.0f, 0.35f));  // towards the sun
const glm::vec3 kSunRadiance(3.0f, 2.8f, 2.5f);
const glm::vec3 kSkyRadiance(0.35f, 0.5f, 0.8f);
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Hit {
  float t = kInf;
  glm::vec3 normal{0.0f};
  glm::vec3 albedo{0.0f};
};

void intersect(const glm::vec3& o, const glm::vec3& d, Hit& hit) {
  if (d.y < -1e-6f) {  // ground plane y = 0
    float t = -o.y / d.y;
    if (t > 1e-4f && t < hit.t) {
      glm::vec3 p = o + t * d;
      bool odd = (static_cast<int>(std::floor(p.x * 1.5f)) + static_cast<int>(std::floor(p.z * 1.5f))) & 1;
      hit = {t, {0.0f, 1.0f, 0.0f}, odd ? glm::vec3(0.75f) : glm::vec3(0.15f, 0.15f, 0.12f)};
    }
  }
  for (const Sphere& s : kSpheres) {
    glm::vec3 oc = o - s.centre;
    float b = glm::dot(oc, d);
    float c = glm::dot(oc, oc) - s.radius * s.radius;
    float disc = b * b - c;
    if (disc < 0.0f) continue;
    float t = -b - std::sqrt(disc);
    if (t > 1e-4f && t < hit.t) hit = {t, glm::normalize(o + t * d - s.centre), s.albedo};
  }
}

// Unit-mean, unit-variance exponential noise: the spread of a 1-spp estimate.
float noise(uint32_t seed, uint32_t frame, uint32_t pixel, uint32_t channel) {
  uint32_t h = seed * 0x9E3779B9u ^ frame * 0x85EBCA6Bu ^ pixel * 0xC2B2AE35u ^ channel * 0x27D4EB2Fu;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  float u = (static_cast<float>(h >> 8) + 0.5f) * (1.0f / 16777216.0f);
  return -std::log(u);
}

}  // namespace

Camera camera_at(int frame, int width, int height) {
  float x = -1.5f + 0.08f * static_cast<float>(frame);
  glm::vec3 eye(x, 1.6f, 4.5f);
  glm::vec3 target(x * 0.3f, 0.5f, 0.0f);
  Camera c;
  c.view = glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(50.0f), static_cast<float>(width) / static_cast<float>(height), 0.1f, 100.0f);
  return c;
}

FrameBuffers render(int frame, int width, int height, uint32_t seed) {
  FrameBuffers fb;
  fb.width = width;
  fb.height = height;
  const size_t n = size_t(width) * height;
  fb.noisy.resize(n * 3);
  fb.clean.resize(n * 3);
  fb.albedo.resize(n * 3);
  fb.normal.resize(n * 3);
  fb.depth.resize(n);
  fb.motion.resize(n * 2);
  fb.position.resize(n * 3);

  const Camera cam = camera_at(frame, width, height);
  const Camera prev = camera_at(frame - 1, width, height);
  const glm::mat4 inv_view = glm::inverse(cam.view);
  const glm::mat4 inv_proj = glm::inverse(cam.projection);
  const glm::mat4 prev_view_proj = prev.projection * prev.view;
  const glm::vec3 eye = glm::vec3(inv_view[3]);

  auto shade_rows = [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < width; ++x) {
        const size_t i = size_t(y) * width + x;
        // Pixel centre to NDC: rows are top-first, NDC y points up.
        glm::vec4 ndc((x + 0.5f) / width * 2.0f - 1.0f, 1.0f - (y + 0.5f) / height * 2.0f, 1.0f, 1.0f);
        glm::vec4 view_dir = inv_proj * ndc;
        glm::vec3 dir = glm::normalize(glm::vec3(inv_view * glm::vec4(glm::vec3(view_dir) / view_dir.w, 0.0f)));
        Hit hit;
        intersect(eye, dir, hit);
        glm::vec3 clean, world;
        if (hit.t == kInf) {
          clean = kSkyRadiance;
          world = eye + dir * 1e4f;  // far point, for motion of the background
          fb.depth[i] = kInf;
        } else {
          world = eye + hit.t * dir;
          Hit shadow;
          intersect(world + hit.normal * 1e-3f, kSunDirection, shadow);
          float sun = shadow.t == kInf ? std::max(0.0f, glm::dot(hit.normal, kSunDirection)) : 0.0f;
          float sky = 0.5f + 0.5f * hit.normal.y;
          clean = hit.albedo * (kSunRadiance * sun + kSkyRadiance * sky);  // Lambertian: albedo/pi times irradiance pi*L
          fb.depth[i] = -(cam.view * glm::vec4(world, 1.0f)).z;
        }
        glm::vec4 prev_clip = prev_view_proj * glm::vec4(world, 1.0f);
        glm::vec2 prev_px((prev_clip.x / prev_clip.w * 0.5f + 0.5f) * width,
                          (0.5f - prev_clip.y / prev_clip.w * 0.5f) * height);
        fb.motion[2 * i] = prev_px.x - (x + 0.5f);
        fb.motion[2 * i + 1] = prev_px.y - (y + 0.5f);
        for (int c = 0; c < 3; ++c) {
          fb.clean[3 * i + c] = clean[c];
          // The sky is noise-free, as a real renderer's miss shader would be.
          fb.noisy[3 * i + c] = hit.t == kInf ? clean[c] : clean[c] * noise(seed, frame, static_cast<uint32_t>(i), c);
          fb.albedo[3 * i + c] = hit.t == kInf ? 1.0f : hit.albedo[c];
          fb.normal[3 * i + c] = hit.t == kInf ? 0.0f : hit.normal[c];
          fb.position[3 * i + c] = world[c];
        }
      }
    }
  };
  unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back(shade_rows, height * t / threads, height * (t + 1) / threads);
  for (auto& t : pool) t.join();
  return fb;
}

}  // namespace dn::synth
