// A frame with an exact truth for the image pipeline: two surfaces meeting at
// a normal edge, a checkered albedo, a shadow edge the guides cannot see, a
// mirror patch (albedo 0) showing fine stripes, a black patch (no light
// reaches it: every sample 0) and a background corner; each
// pixel's radiance the truth times the mean of `spp` samples uniform in
// [0, 2] (seeded).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace dn::test {

struct ImageScene {
  int width = 64, height = 48;
  std::vector<float> truth, albedo, normal, depth;  // 3, 3, 3, 1 per pixel

  ImageScene() {
    const int n = width * height;
    truth.resize(3 * n), albedo.resize(3 * n), normal.resize(3 * n), depth.resize(n);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const int i = y * width + x;
        const bool left = x < 40, background = x >= 56 && y >= 36;
        const bool mirror = x >= 44 && x < 56 && y >= 4 && y < 20;
        const float light = y < 24 ? 1.0f : 0.25f;  // the shadow edge
        const float a = left ? (((x / 8) + (y / 8)) % 2 ? 0.8f : 0.2f) : mirror ? 0.0f : 0.5f;
        float t = a * light;
        if (mirror) t = (x / 2) % 2 ? 2.0f : 0.2f;  // what the mirror shows
        if (background) t = 0.1f;
        if (x < 8 && y >= 40) t = 0.0f;  // the black patch
        for (int k = 0; k < 3; ++k) {
          truth[3 * i + k] = t * (k == 0 ? 1.0f : k == 1 ? 0.9f : 0.7f);
          albedo[3 * i + k] = background ? 0.0f : a;
        }
        normal[3 * i + 0] = left ? 0.0f : 1.0f;
        normal[3 * i + 2] = left ? 1.0f : 0.0f;
        depth[i] = background ? 0.0f : left ? 3.0f : 4.0f;
      }
  }

  // Root-mean-square error of an rgb frame against the truth.
  double rmse(const std::vector<float>& rgb) const {
    double e = 0.0;
    for (size_t i = 0; i < truth.size(); ++i) e += (double(rgb[i]) - truth[i]) * (double(rgb[i]) - truth[i]);
    return std::sqrt(e / double(truth.size()));
  }

  std::vector<float> noisy(int spp, uint32_t seed) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 2.0f);
    std::vector<float> out(truth.size());
    for (size_t i = 0; i < truth.size(); i += 3) {
      float m = 0.0f;
      for (int s = 0; s < spp; ++s) m += u(rng);
      for (int k = 0; k < 3; ++k) out[i + k] = truth[i + k] * m / static_cast<float>(spp);
    }
    return out;
  }
};

}  // namespace dn::test
