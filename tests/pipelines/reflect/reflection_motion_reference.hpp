// CPU reference of the reflection motion search of paper 001 (Voorhuis,
// "Beyond SVGF", Alg. 1 and Eq. 1-3; ../shared/papers/IMPLEMENTATION-NOTES.md
// C.2 R3, C.3, C.4): for pixel p, the pixel q of the previous frame whose
// first non-specular hit position (pure specular, Eq. 1) or representative
// ray (glossy, Eq. 4-5) is closest to p's, found by a diamond search from
// two starts (p itself and p + the primary motion; a third, the virtual
// point's motion, as an option), then refined to
// sub-pixel precision. Double precision; reflect_motion's pass is compared
// with it.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

namespace dn::test::reflect {

// A per-pixel field of world positions (the first non-specular hit along the
// mirror chain); pixels without one (not a mirror, background) are invalid.
struct HitField {
  int width = 0, height = 0;
  std::vector<std::array<double, 3>> position;  // row-major, y down
  std::vector<char> valid;
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

// Glossy pixels (paper 001 §4.2.1): the representative ray (origin at the
// primary hit, unit mirror direction) and the length of this frame's sampled
// secondary segment.
struct RayField {
  int width = 0, height = 0;
  std::vector<std::array<double, 3>> origin, direction;
  std::vector<double> depth;
  std::vector<char> valid;
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

inline constexpr double kInvalid = std::numeric_limits<double>::infinity();

// Eq. 1: |W_p - PrevW_q|; +inf when q is off-screen or either has no hit.
double hit_distance(const HitField& current, const HitField& previous, int px, int py, int qx, int qy);

// Eq. 4-5: approxhit(r) = r.o + r.d depth; of the two rays the one with the
// smaller depth is r_near; the distance is that of approxhit(r_near) from
// the ray r_far: |r_far.d x (approxhit(r_near) - r_far.o)|, or the distance
// to r_far.o for a point behind it (the line's distance alone also matches
// hits behind the mirror: docs/pipelines.md). +inf when q is off-screen or
// either ray is missing (or has no finite depth).
double ray_distance(const RayField& current, const RayField& previous, int px, int py, int qx, int qy);

// The large diamond pattern (LDSP), scaled by the step size: the notes'
// reading of Cheng et al. (centre + (+-2, 0), (0, +-2), so the final small
// diamond at +-1 is not redundant), or the four diagonals (+-1, +-1).
enum class LargeDiamond { Axes2, Diagonals };

struct SearchOptions {
  LargeDiamond large = LargeDiamond::Axes2;
  int first_step = 4;       // 4 -> 2 -> 1
  int max_iterations = 32;  // cap against ties (the search also stops on no strict improvement at step 1)
  // A third start, p's virtual point's motion (reflect.virtual_start, NRD's
  // virtual motion); NaN: none.
  std::array<double, 2> virtual_motion{std::numeric_limits<double>::quiet_NaN(),
                                       std::numeric_limits<double>::quiet_NaN()};
};

struct IntegerMatch {
  int x = 0, y = 0;          // the best previous-frame pixel
  double distance = kInvalid;
  int evaluations = 0;       // distance evaluations (cost)
};

// Alg. 1 for pixel p. `motion` is p's primary motion in the service's
// convention (PixelsToPrevious: p_prev = p + motion); the second start is
// the pixel nearest to p + motion.
IntegerMatch diamond_search(const HitField& current, const HitField& previous, int px, int py,
                            const std::array<double, 2>& motion, const SearchOptions& options = {});

IntegerMatch diamond_search(const RayField& current, const RayField& previous, int px, int py,
                            const std::array<double, 2>& motion, const SearchOptions& options = {});

// Every previous pixel within +-radius of p: the brute-force oracle.
IntegerMatch brute_force_search(const HitField& current, const HitField& previous, int px, int py, int radius);
IntegerMatch brute_force_search(const RayField& current, const RayField& previous, int px, int py, int radius);

struct SubpixelMatch {
  double x = 0.0, y = 0.0;  // continuous previous-frame pixel position (pixel centres at integers)
  std::array<double, 4> weights{};  // of the chosen 2x2 block, >= 0, summing to 1
  bool fell_back = false;           // guards: no valid 2x2 block, or all weights 0
};

// Eq. 2-3 around the integer match: among the four 2x2 blocks that contain
// it, the one with the smallest summed distance; each of its pixels weighted
// by the product of the other three's distances (distances divided by the
// match's distance first, so the products stay in range). One zero distance
// returns that pixel exactly; two or more, or a block with an invalid pixel
// only, fall back to the integer match.
SubpixelMatch refine_subpixel(const HitField& current, const HitField& previous, int px, int py,
                              const IntegerMatch& match);
SubpixelMatch refine_subpixel(const RayField& current, const RayField& previous, int px, int py,
                              const IntegerMatch& match);

}  // namespace dn::test::reflect
