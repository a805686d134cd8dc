#include "reflection_motion_reference.hpp"

#include <cmath>
#include <functional>

namespace dn::test::reflect {

double hit_distance(const HitField& current, const HitField& previous, int px, int py, int qx, int qy) {
  if (!current.inside(px, py) || !previous.inside(qx, qy)) return kInvalid;
  const size_t p = current.index(px, py), q = previous.index(qx, qy);
  if (!current.valid[p] || !previous.valid[q]) return kInvalid;
  const auto& a = current.position[p];
  const auto& b = previous.position[q];
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

double ray_distance(const RayField& current, const RayField& previous, int px, int py, int qx, int qy) {
  if (!current.inside(px, py) || !previous.inside(qx, qy)) return kInvalid;
  const size_t p = current.index(px, py), q = previous.index(qx, qy);
  if (!current.valid[p] || !previous.valid[q] || !std::isfinite(current.depth[p]) || !std::isfinite(previous.depth[q]))
    return kInvalid;
  const bool p_near = current.depth[p] <= previous.depth[q];
  const auto& no = p_near ? current.origin[p] : previous.origin[q];
  const auto& nd = p_near ? current.direction[p] : previous.direction[q];
  const double ndepth = p_near ? current.depth[p] : previous.depth[q];
  const auto& fo = p_near ? previous.origin[q] : current.origin[p];
  const auto& fd = p_near ? previous.direction[q] : current.direction[p];
  // v = approxhit(r_near) - r_far.o as (no - fo) + depth nd, so that two
  // equal rays give exactly 0 (fd x nd = 0 then).
  const double b[3] = {no[0] - fo[0], no[1] - fo[1], no[2] - fo[2]};
  auto cross = [](const auto& a, const auto& c) {
    return std::array<double, 3>{a[1] * c[2] - a[2] * c[1], a[2] * c[0] - a[0] * c[2], a[0] * c[1] - a[1] * c[0]};
  };
  auto dot = [](const auto& a, const auto& c) { return a[0] * c[0] + a[1] * c[1] + a[2] * c[2]; };
  // A ray, not a line: a point behind r_far's origin is measured from the
  // origin (the line alone would also match points on the extension behind
  // the mirror, other walls' hits).
  if (dot(b, fd) + ndepth * dot(nd, fd) < 0.0) {
    const double v[3] = {b[0] + ndepth * nd[0], b[1] + ndepth * nd[1], b[2] + ndepth * nd[2]};
    return std::sqrt(dot(v, v));
  }
  const auto cb = cross(fd, b), cn = cross(fd, nd);
  const double c[3] = {cb[0] + ndepth * cn[0], cb[1] + ndepth * cn[1], cb[2] + ndepth * cn[2]};
  return std::sqrt(dot(c, c));
}

namespace {

// Distance of p's feature to previous pixel q's.
using Distance = std::function<double(int qx, int qy)>;

struct Search {
  const Distance& distance;
  IntegerMatch best;

  // Strict improvement only: ties keep the earlier candidate.
  bool consider(int qx, int qy) {
    ++best.evaluations;
    const double d = distance(qx, qy);
    if (!(d < best.distance)) return false;
    best.x = qx, best.y = qy, best.distance = d;
    return true;
  }
};

IntegerMatch diamond(const Distance& distance, int px, int py, const std::array<double, 2>& motion,
                     const SearchOptions& options) {
  Search s{distance, {}};
  s.best.x = px, s.best.y = py;
  s.consider(px, py);  // start 1: the same pixel
  // Starts 2 and 3: the pixels nearest p + the primary motion and p + the
  // virtual point's motion, where the motion is usable (finite, within 2^20 px).
  for (const auto& m : {motion, options.virtual_motion})
    if (std::isfinite(m[0]) && std::isfinite(m[1]) && std::fabs(m[0]) <= 1048576.0 && std::fabs(m[1]) <= 1048576.0)
      s.consider(int(std::floor(px + m[0] + 0.5)), int(std::floor(py + m[1] + 0.5)));
  static constexpr int axes[4][2] = {{2, 0}, {-2, 0}, {0, 2}, {0, -2}};
  static constexpr int diagonals[4][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
  const auto& large = options.large == LargeDiamond::Axes2 ? axes : diagonals;
  int step = options.first_step;
  int cx = s.best.x, cy = s.best.y;
  for (int it = 0; it < options.max_iterations; ++it) {
    for (const auto& o : large) s.consider(cx + o[0] * step, cy + o[1] * step);
    if (s.best.x == cx && s.best.y == cy) {
      if (step == 1) break;
      step /= 2;
    }
    cx = s.best.x, cy = s.best.y;
  }
  // One final small diamond (SDSP) step.
  for (const auto& o : {std::array{1, 0}, std::array{-1, 0}, std::array{0, 1}, std::array{0, -1}})
    s.consider(cx + o[0], cy + o[1]);
  return s.best;
}

IntegerMatch brute_force(const Distance& distance, int px, int py, int radius) {
  Search s{distance, {}};
  s.best.x = px, s.best.y = py;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) s.consider(px + dx, py + dy);
  return s.best;
}

SubpixelMatch refine(const Distance& distance, const IntegerMatch& match) {
  SubpixelMatch out;
  out.x = match.x, out.y = match.y;
  out.weights = {1.0, 0.0, 0.0, 0.0};
  if (!std::isfinite(match.distance)) {
    out.fell_back = true;
    return out;
  }
  if (match.distance == 0.0) return out;  // exact: the pixel itself
  // The four 2x2 blocks holding the match: origins (match + (ox, oy)), ox, oy in {-1, 0}.
  double best_sum = kInvalid;
  int bx = 0, by = 0;
  std::array<double, 4> best_d{};
  for (int oy = -1; oy <= 0; ++oy)
    for (int ox = -1; ox <= 0; ++ox) {
      std::array<double, 4> d;
      double sum = 0.0;
      for (int k = 0; k < 4; ++k) {
        d[k] = distance(match.x + ox + (k & 1), match.y + oy + (k >> 1)) / match.distance;
        sum += d[k];
      }
      if (sum < best_sum) best_sum = sum, bx = match.x + ox, by = match.y + oy, best_d = d;
    }
  if (!std::isfinite(best_sum)) {  // every block has an invalid pixel
    out.fell_back = true;
    return out;
  }
  std::array<double, 4> w;
  double total = 0.0;
  for (int k = 0; k < 4; ++k) {
    w[k] = 1.0;
    for (int j = 0; j < 4; ++j)
      if (j != k) w[k] *= best_d[j];
    total += w[k];
  }
  if (!(total > 0.0)) {  // two or more zero distances
    out.fell_back = true;
    return out;
  }
  out.x = out.y = 0.0;
  for (int k = 0; k < 4; ++k) {
    out.weights[k] = w[k] / total;
    out.x += out.weights[k] * (bx + (k & 1));
    out.y += out.weights[k] * (by + (k >> 1));
  }
  return out;
}

}  // namespace

IntegerMatch diamond_search(const HitField& current, const HitField& previous, int px, int py,
                            const std::array<double, 2>& motion, const SearchOptions& options) {
  return diamond([&](int qx, int qy) { return hit_distance(current, previous, px, py, qx, qy); }, px, py, motion,
                 options);
}
IntegerMatch diamond_search(const RayField& current, const RayField& previous, int px, int py,
                            const std::array<double, 2>& motion, const SearchOptions& options) {
  return diamond([&](int qx, int qy) { return ray_distance(current, previous, px, py, qx, qy); }, px, py, motion,
                 options);
}
IntegerMatch brute_force_search(const HitField& current, const HitField& previous, int px, int py, int radius) {
  return brute_force([&](int qx, int qy) { return hit_distance(current, previous, px, py, qx, qy); }, px, py, radius);
}
IntegerMatch brute_force_search(const RayField& current, const RayField& previous, int px, int py, int radius) {
  return brute_force([&](int qx, int qy) { return ray_distance(current, previous, px, py, qx, qy); }, px, py, radius);
}
SubpixelMatch refine_subpixel(const HitField& current, const HitField& previous, int px, int py,
                              const IntegerMatch& match) {
  return refine([&](int qx, int qy) { return hit_distance(current, previous, px, py, qx, qy); }, match);
}
SubpixelMatch refine_subpixel(const RayField& current, const RayField& previous, int px, int py,
                              const IntegerMatch& match) {
  return refine([&](int qx, int qy) { return ray_distance(current, previous, px, py, qx, qy); }, match);
}

}  // namespace dn::test::reflect
