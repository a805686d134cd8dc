#include "svgf_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dn::test {
namespace {

// A still running mean of more samples than this is where the filter starts (DN_STILL_FILTER_FROM).
constexpr double kStillFilterFrom = 8.0;
// From this many samples a still running mean is the guard's target (DN_STILL_MIN_SAMPLES).
constexpr double kStillMinSamples = 4.0;
// Over how many samples from there its weight rises to 1 (DN_STILL_RAMP).
constexpr double kStillRamp = 4.0;
// Below this history length a still pixel's guard is widened (DN_GUARD_SURE_LENGTH).
constexpr double kGuardSureLength = 8.0;

double luminance(const double* c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

// The guide rules of docs/pipelines.md "Sanitize rule" (the device's fp32
// bounds): depth within [FLT_MIN, 1e18], albedo-like modulators within
// [1e-3, 1e3] (else 1), a normal whose fp32 |n|^2 would overflow is none,
// motion beyond 2^20 px is none, a non-finite roughness is 1.
bool foreground(double z) { return std::isfinite(z) && z >= std::numeric_limits<float>::min() && z <= 1e18; }
double guarded(double a) { return std::isfinite(a) && a >= static_cast<double>(1e-3f) && a <= 1e3 ? a : 1.0; }
// The largest of pixel i's three components, each rounded to fp32 as the device reads it.
double largest_f32(const std::vector<double>& v, int i) {
  return std::max({double(float(v[3 * i])), double(float(v[3 * i + 1])), double(float(v[3 * i + 2]))});
}
bool usable_normal(const double* n) {
  const double n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  return std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]) && n2 <= std::numeric_limits<float>::max();
}
bool usable_motion(double mx, double my) {
  return std::isfinite(mx) && std::isfinite(my) && std::fabs(mx) <= 1048576.0 && std::fabs(my) <= 1048576.0;
}
bool sampled(double count) { return std::isfinite(count) && count > 0.0; }
double sanitized_roughness(double r) { return std::isfinite(r) ? std::clamp(r, 0.0, 1.0) : 1.0; }

// Stored history normal: octahedral map quantized to two snorm16 and back.
void quantize_normal(const double* in, double* out) {
  const double l1 = std::fabs(in[0]) + std::fabs(in[1]) + std::fabs(in[2]);
  double ex = in[0] / l1, ey = in[1] / l1;
  const double ez = in[2] / l1;
  auto sign = [](double v) { return v >= 0.0 ? 1.0 : -1.0; };
  if (ez < 0.0) {
    const double ox = ex, oy = ey;
    ex = (1.0 - std::fabs(oy)) * sign(ox);
    ey = (1.0 - std::fabs(ox)) * sign(oy);
  }
  auto snorm = [](double v) {
    const double q = std::round(std::clamp(v, -1.0, 1.0) * 32767.0);
    return std::clamp(q / 32767.0, -1.0, 1.0);
  };
  double x = snorm(ex), y = snorm(ey);
  const double z = 1.0 - std::fabs(x) - std::fabs(y);
  if (z < 0.0) {
    const double ox = x, oy = y;
    x = (1.0 - std::fabs(oy)) * sign(ox);
    y = (1.0 - std::fabs(ox)) * sign(oy);
  }
  const double len = std::sqrt(x * x + y * y + z * z);
  out[0] = x / len;
  out[1] = y / len;
  out[2] = z / len;
}

double distance3(const double* a, const double* b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

}  // namespace

void apply_parameters(SvgfParams& p, const std::vector<pipelines::ParameterValue>& values) {
  for (const auto& q : values) {
    if (q.name == "alpha_colour") p.alpha_colour = q.value;
    if (q.name == "alpha_moments") p.alpha_moments = q.value;
    if (q.name == "max_history") p.max_history = q.value;
    if (q.name == "atrous_iterations") p.atrous_iterations = static_cast<int>(q.value);
    if (q.name == "feedback_tap") p.feedback_tap = static_cast<int>(q.value);
    if (q.name == "phi_colour") p.phi_colour = q.value;
    if (q.name == "phi_normal") p.phi_normal = q.value;
    if (q.name == "phi_depth") p.phi_depth = q.value;
    if (q.name == "taa_alpha") p.taa_alpha = q.value;
    if (q.name == "taa_static_alpha") p.taa_static_alpha = q.value;
    if (q.name == "clip_roughness") p.clip_roughness = q.value;
    if (q.name == "variance_of_mean") p.variance_of_mean = static_cast<int>(q.value);
    if (q.name == "luminance_ramp") p.luminance_ramp = static_cast<int>(q.value);
    if (q.name == "harm_guard") p.harm_guard = q.value;
    if (q.name == "keep_unexplained") p.keep_unexplained = static_cast<int>(q.value);
    if (q.name == "converge_still") p.converge_still = q.value;
    if (q.name == "propagate_variance") p.propagate_variance = static_cast<int>(q.value);
    if (q.name == "step_order") p.finest_first = q.value == 0.0;
    if (q.name == "luminance_form") p.luminance_form = static_cast<int>(q.value);
    if (q.name == "sigma_luminance") p.sigma_luminance = q.value;
    if (q.name == "epsilon_luminance") p.epsilon_luminance = q.value;
    if (q.name == "luminance_min_age") p.luminance_min_age = q.value;
    if (q.name == "luminance_ramp_in") p.luminance_ramp_in = q.value;
    if (q.name == "display_lag") p.display_lag = q.value != 0.0;
  }
}

SvgfReference::SvgfReference(int width, int height, SvgfParams params) : w_(width), h_(height), p_(params) {}

std::vector<double> SvgfReference::step(const SvgfFrame& f) {
  const int w = w_, h = h_, n = w * h;
  const bool reset = f.reset || !has_history_;
  const int iterations = p_.atrous_iterations;
  const int tap = std::min(p_.feedback_tap, std::max(iterations - 1, 0));
  // Fewer than one sample per pixel: the pixels without a sample this frame.
  const bool masked = !f.sample_count.empty();

  // Inputs: sanitized radiance (split: diffuse, specular), guarded albedo, depth, sanitized normals.
  const bool split = !f.diffuse.empty();
  auto sanitize = [&](const std::vector<double>& in) {
    std::vector<double> out(3 * n);
    for (int i = 0; i < 3 * n; ++i) out[i] = (std::isfinite(in[i]) && in[i] > 0.0 && in[i] <= 1e12) ? in[i] : 0.0;
    return out;
  };
  std::vector<double> a(3 * n), nrm(3 * n, 0.0), z(n);
  std::vector<bool> fg(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      a[3 * i + k] = guarded(f.albedo[3 * i + k]);
    }
    z[i] = f.depth[i];
    fg[i] = foreground(z[i]);
    if (usable_normal(&f.normal[3 * i]))
      for (int k = 0; k < 3; ++k) nrm[3 * i + k] = f.normal[3 * i + k];
  }
  // Gradients: per axis min over the inside foreground neighbours of |dz| and
  // of |dn| (independently), then max over the axes.
  std::vector<double> dz(n, 0.0), dn(n, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      if (!fg[i]) continue;
      for (int axis = 0; axis < 2; ++axis) {
        double bz = 1e300, bn = 1e300;
        bool any = false;
        for (int side : {-1, 1}) {
          const int qx = x + (axis == 0 ? side : 0), qy = y + (axis == 1 ? side : 0);
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
          const int q = qy * w + qx;
          if (!fg[q]) continue;
          any = true;
          bz = std::min(bz, std::fabs(z[q] - z[i]));
          bn = std::min(bn, distance3(&nrm[3 * q], &nrm[3 * i]));
        }
        if (any) {
          dz[i] = std::max(dz[i], bz);
          dn[i] = std::max(dn[i], bn);
        }
      }
    }

  // The geometry history the next frame reads: depth and quantized normal of
  // the foreground pixels with a normal; minus the depth without one (only
  // the still mean goes on from it).
  std::vector<double> hz(n, 0.0), hn(3 * n, 0.0);
  for (int i = 0; i < n; ++i) {
    const double* nc = &nrm[3 * i];
    if (!fg[i]) continue;
    if (nc[0] * nc[0] + nc[1] * nc[1] + nc[2] * nc[2] > 0.0) {
      hz[i] = z[i];
      quantize_normal(nc, &hn[3 * i]);
    } else {
      hz[i] = -z[i];
    }
  }

  // The edge-stopping normals of the variance and a-trous passes are the
  // device's per-frame guide: the octahedral snorm16x2 encoding (unit length);
  // a zero (sanitized) normal stays zero and takes no tap.
  std::vector<double> gn(3 * n, 0.0);
  for (int i = 0; i < n; ++i)
    if (nrm[3 * i] * nrm[3 * i] + nrm[3 * i + 1] * nrm[3 * i + 1] + nrm[3 * i + 2] * nrm[3 * i + 2] > 0.0)
      quantize_normal(&nrm[3 * i], &gn[3 * i]);
  auto normal_weight = [&](int i, int q) {
    const double cosv =
        std::max(0.0, gn[3 * i] * gn[3 * q] + gn[3 * i + 1] * gn[3 * q + 1] + gn[3 * i + 2] * gn[3 * q + 2]);
    return std::pow(std::min(cosv, 1.0), p_.phi_normal);
  };

  // Passes 1-3 over one signal c (sanitized) demodulated by demod; returns the
  // last a-trous result (rgb, variance) and updates the chain's history.
  // History clipping (pass 1, clipped chains): the box is the per-channel
  // min/max over the 5x5 pixels around p (inside) of the 7x7 binomial
  // Gaussian of the demodulated current signal over foreground pixels, where
  // that Gaussian has a foreground tap.
  auto clip_boxes = [&](const std::vector<double>& d, std::vector<double>& lo, std::vector<double>& hi,
                        std::vector<bool>& has, std::vector<double>& g, std::vector<bool>& gv) {
    static const double b[7] = {1, 6, 15, 20, 15, 6, 1};
    g.assign(3 * n, 0.0);
    gv.assign(n, false);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double s[3] = {0, 0, 0}, sw = 0;
        for (int yy = -3; yy <= 3; ++yy)
          for (int xx = -3; xx <= 3; ++xx) {
            const int qx = x + xx, qy = y + yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h || !fg[qy * w + qx]) continue;
            const double wt = b[xx + 3] * b[yy + 3];
            for (int k = 0; k < 3; ++k) s[k] += wt * d[3 * (qy * w + qx) + k];
            sw += wt;
          }
        const int i = y * w + x;
        gv[i] = sw > 0.0;
        for (int k = 0; k < 3; ++k) g[3 * i + k] = sw > 0.0 ? s[k] / sw : 0.0;
      }
    lo.assign(3 * n, 1e300);
    hi.assign(3 * n, -1e300);
    has.assign(n, false);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int i = y * w + x;
        for (int yy = -2; yy <= 2; ++yy)
          for (int xx = -2; xx <= 2; ++xx) {
            const int qx = x + xx, qy = y + yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h || !gv[qy * w + qx]) continue;
            const int q = qy * w + qx;
            has[i] = true;
            for (int k = 0; k < 3; ++k) {
              lo[3 * i + k] = std::min(lo[3 * i + k], g[3 * q + k]);
              hi[3 * i + k] = std::max(hi[3 * i + k], g[3 * q + k]);
            }
          }
      }
  };
  // ring_fill.glsl: the mean over the smallest square ring around (x, y),
  // radius 1 to 8, holding any pixel q for which source(q, value) is true.
  auto ring_fill = [&](int x, int y, auto source, double* mean) {
    for (int r = 1; r <= 8; ++r) {
      double sum[3] = {0, 0, 0}, v[3];
      int count = 0;
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; dx += (std::abs(dy) == r ? 1 : 2 * r)) {
          const int qx = x + dx, qy = y + dy;
          if (qx < 0 || qy < 0 || qx >= w || qy >= h || !source(qy * w + qx, v)) continue;
          for (int k = 0; k < 3; ++k) sum[k] += v[k];
          ++count;
        }
      if (count > 0) {
        for (int k = 0; k < 3; ++k) mean[k] = sum[k] / count;
        return true;
      }
    }
    return false;
  };
  auto has_normal_at = [&](int q) {
    return nrm[3 * q] * nrm[3 * q] + nrm[3 * q + 1] * nrm[3 * q + 1] + nrm[3 * q + 2] * nrm[3 * q + 2] > 0.0;
  };
  auto clipped_here = [&](int i) { return sanitized_roughness(f.roughness[i]) < p_.clip_roughness; };

  // What a sample's variance is divided by (variance_of_mean): the samples a
  // temporal mean of length l averages, l while the blend weight is 1/l,
  // then the exponential average's (2 - alpha) / alpha; for a still running
  // mean of still_n samples (more than 8) handed to the filter, still_n
  // sqrt(still_n / 8): its edge-stopping narrows faster than its noise falls.
  auto variance_divisor = [&](double l, double still_n) {
    if (!p_.variance_of_mean) return 1.0;
    if (still_n > kStillFilterFrom) return still_n * std::sqrt(still_n / kStillFilterFrom);
    const double a = p_.alpha_colour;
    return a > 0.0 ? std::clamp(l, 1.0, (2.0 - a) / a) : std::max(l, 1.0);
  };

  // converge_still (with the guard): a still pixel's running mean of its own
  // samples goes on where its history is valid and its motion below 0.005 px,
  // else restarts from the sample; without a sample it is kept while it
  // would go on, else none; background has none.
  const bool keeps_still = p_.converge_still > 0.0 && p_.harm_guard > 0.0 && iterations > 0;
  auto update_still = [&](Chain& ch, int i, const double* sample, bool has_sample, bool continues) {
    if (!keeps_still) return;
    if (ch.still_n.empty()) {
      ch.still_mean.assign(3 * n, 0.0);
      ch.still_n.assign(n, 0.0);
      ch.still_m2.assign(n, 0.0);
    }
    if (!has_sample) {
      if (!continues) ch.still_n[i] = ch.still_m2[i] = 0.0;
      return;
    }
    const double k = continues && ch.still_n[i] > 0.0 ? std::min(ch.still_n[i] + 1.0, 65536.0) : 1.0;
    const double before = luminance(&ch.still_mean[3 * i]);
    for (int c = 0; c < 3; ++c)
      ch.still_mean[3 * i + c] = k == 1.0 ? sample[c] : ch.still_mean[3 * i + c] + (sample[c] - ch.still_mean[3 * i + c]) / k;
    // Welford's M2 of the luminance (at the cap, decaying with the mean).
    const double l = luminance(sample), m2 = k == ch.still_n[i] ? ch.still_m2[i] * (1.0 - 1.0 / k) : ch.still_m2[i];
    ch.still_m2[i] = k == 1.0 ? 0.0 : m2 + (l - before) * (l - luminance(&ch.still_mean[3 * i]));
    ch.still_n[i] = k;
  };

  // The still mean's change test: b, the luminance of the current samples
  // over the 3x3 foreground pixels averaged without its largest and
  // smallest, and its variance from their spread (over count - 2), keep b's
  // running mean and M2 and the recent means (exponential, weight
  // max(1/k, 1/4)) of b and of that variance; from 8 samples on, the recent
  // b beyond t standard deviations of itself from the running mean (the
  // larger of the M2's before b and the recent spread's, times
  // a / (2 - a) + 1/n), plus 1e-3 of it, restarts the still mean and the
  // history; t = 3 darker, 4 brighter. Single precision, as on the device.
  auto still_unchanged = [&](Chain& ch, int i, float b, float spread, bool continues) {
    if (ch.change.empty()) ch.change.assign(4 * n, 0.0f);
    float* s = &ch.change[4 * i];
    const float cn = ch.still_n.empty() ? 0.0f : float(ch.still_n[i]);
    auto restart = [&] {
      s[0] = s[2] = b;
      s[1] = 0.0f;
      s[3] = spread;
      return false;
    };
    if (!continues || !(cn > 0.0f)) return restart();
    const float k = std::min(cn + 1.0f, 65536.0f);
    const float a = std::max(1.0f / k, 0.25f);
    const float recent = s[2] * (1.0f - a) + b * a, recent_spread = s[3] * (1.0f - a) + spread * a;
    const float dev = recent - s[0], bound = 1e-3f * std::max(recent, s[0]);
    const float t2 = dev < 0.0f ? 9.0f : 16.0f;
    const float v = std::max(cn > 1.0f ? s[1] / (cn - 1.0f) : 0.0f, recent_spread);
    if (cn >= 8.0f && dev * dev > t2 * v * (a / (2.0f - a) + 1.0f / cn) + bound * bound) return restart();
    const float mean = s[0] * (1.0f - 1.0f / k) + b * (1.0f / k);
    s[1] = (k == cn ? s[1] * (1.0f - 1.0f / k) : s[1]) + (b - s[0]) * (b - mean);
    s[0] = mean;
    s[2] = recent;
    s[3] = recent_spread;
    return true;
  };

  // A sample the sanitizer changed (not finite, negative, above 1e12) is none for the still mean.
  auto valid_samples = [&](const std::vector<double>& plane) {
    std::vector<bool> ok(n);
    for (int i = 0; i < n; ++i) {
      ok[i] = true;
      for (int k = 0; k < 3; ++k) ok[i] = ok[i] && std::isfinite(plane[3 * i + k]) && plane[3 * i + k] >= 0.0 && plane[3 * i + k] <= 1e12;
    }
    return ok;
  };

  auto filter = [&](Chain& ch, const std::vector<double>& c, const std::vector<double>& demod, bool clip,
                    const std::vector<bool>& sample_ok) {
  const std::vector<double>& colour_ = ch.colour;
  const std::vector<double>& length_ = ch.length;
  const std::vector<double>& m1_ = ch.m1;
  const std::vector<double>& m2_ = ch.m2;
  // Pass 1: reprojection, history clipping and temporal integration.
  std::vector<double> d(3 * n), colour(3 * n), len(n), m1(n), m2(n);
  std::vector<double> divisor(n, 1.0);  // each temporal colour's variance divisor (variance_divisor)
  for (int i = 0; i < 3 * n; ++i) d[i] = c[i] / demod[i];
  std::vector<double> lo, hi, pre;
  std::vector<bool> has_box, has_pre;
  clip = clip && p_.clip_roughness > 0.0 && !f.roughness.empty();
  if (clip) clip_boxes(d, lo, hi, has_box, pre, has_pre);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      const double l = luminance(&d[3 * i]);
      if (!fg[i]) {
        double bg[3] = {d[3 * i], d[3 * i + 1], d[3 * i + 2]};
        // Below one sample per pixel an unsampled background pixel shows the
        // mean of the nearest ring of sampled background pixels.
        if (masked && !sampled(f.sample_count[i]))
          ring_fill(x, y, [&](int q, double* v) {
            for (int k = 0; k < 3; ++k) v[k] = d[3 * q + k];
            return sampled(f.sample_count[q]) && !fg[q];
          }, bg);
        for (int k = 0; k < 3; ++k) colour[3 * i + k] = bg[k];
        len[i] = 0.0;
        m1[i] = luminance(bg);
        m2[i] = m1[i] * m1[i];
        update_still(ch, i, bg, false, false);
        continue;
      }
      const double* nc = &nrm[3 * i];
      const bool has_normal = nc[0] * nc[0] + nc[1] * nc[1] + nc[2] * nc[2] > 0.0;
      const double mvx = f.motion[2 * i], mvy = f.motion[2 * i + 1];
      double pc[3] = {0, 0, 0}, pm1 = 0, pm2 = 0, plen = 0;
      bool valid = false;
      const double px = x + 0.5 + mvx, py = y + 0.5 + mvy;  // previous position, centres at +0.5
      if (!reset && has_normal && usable_motion(mvx, mvy) && px - 0.5 > -1.0 && py - 0.5 > -1.0 &&
          px - 0.5 < w && py - 0.5 < h) {
        double sc[3] = {0, 0, 0}, sm1 = 0, sm2 = 0, sl = 0, sw = 0;
        auto add = [&](int qx, int qy, double wt) {
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) return;
          const int q = qy * w + qx;
          if (!(z_[q] > 0.0)) return;
          if (std::fabs(z[i] - z_[q]) / (dz[i] + 0.01) > 10.0) return;
          if (distance3(nc, &n_[3 * q]) / (dn[i] + 0.01) > 16.0) return;
          for (int k = 0; k < 3; ++k) sc[k] += wt * colour_[3 * q + k];
          sm1 += wt * m1_[q];
          sm2 += wt * m2_[q];
          sl += wt * length_[q];
          sw += wt;
        };
        const double fx = px - 0.5, fy = py - 0.5;
        const double bx = std::floor(fx), by = std::floor(fy), tx = fx - bx, ty = fy - by;
        const int ix = static_cast<int>(bx), iy = static_cast<int>(by);
        add(ix, iy, (1 - tx) * (1 - ty));
        add(ix + 1, iy, tx * (1 - ty));
        add(ix, iy + 1, (1 - tx) * ty);
        add(ix + 1, iy + 1, tx * ty);
        // Falcor's fallback, the 3x3 box of valid taps around the pixel containing p_prev; not when masked: a pixel
        // without history there mostly had no sample yet, and missing values are not filled from neighbours.
        if (sw < 1e-3 && !masked) {
          sc[0] = sc[1] = sc[2] = sm1 = sm2 = sl = sw = 0.0;
          const int cx = static_cast<int>(std::floor(px)), cy = static_cast<int>(std::floor(py));
          for (int yy = -1; yy <= 1; ++yy)
            for (int xx = -1; xx <= 1; ++xx) add(cx + xx, cy + yy, 1.0);
        }
        if (sw > 0.0) {
          valid = true;
          for (int k = 0; k < 3; ++k) pc[k] = sc[k] / sw;
          pm1 = sm1 / sw;
          pm2 = sm2 / sw;
          plen = std::floor(sl / sw + 0.5);
        }
      }
      // Clipped chains: reject a history that the prefiltered current, p's
      // own current value and at least 3 of its 8 raw neighbours (on p's side)
      // contradict, each beyond 4 sigma of the history's noise plus half the
      // larger luminance; sigma: the largest of p's reprojected moments and
      // the 3x3 history pixels around p's previous pixel.
      // Threshold decisions: made in single precision, as the device makes
      // them, so rounding does not flip them (m2 - m1^2 cancels in fp32).
      const bool surface_kept = valid;  // the still mean goes on through the clip's rejection
      const int prev_x = static_cast<int>(std::floor(px)), prev_y = static_cast<int>(std::floor(py));
      auto moments_sigma = [](float m1, float m2) {  // clip.glsl's dn_moments_sigma
        const float v = m2 - m1 * m1;
        return v > 1e-6f * m1 * m1 ? std::sqrt(v) : 0.0f;
      };
      auto history_sigma = [&]() {
        float sigma = moments_sigma(float(pm1), float(pm2));
        for (int yy = -1; yy <= 1; ++yy)
          for (int xx = -1; xx <= 1; ++xx) {
            const int qx = prev_x + xx, qy = prev_y + yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h || !(z_[qy * w + qx] > 0.0)) continue;
            sigma = std::max(sigma, moments_sigma(float(m1_[qy * w + qx]), float(m2_[qy * w + qx])));
          }
        return sigma;
      };
      if (valid && clip && clipped_here(i) && has_pre[i]) {
        const float lh = float(luminance(pc)), sigma = history_sigma();
        auto contradicts = [&](float lc) {
          return std::fabs(lc - lh) > 4.0f * sigma + 0.5f * std::max(lc, lh);
        };
        const float l = float(luminance(&d[3 * i]));
        if (contradicts(float(luminance(&pre[3 * i]))) && contradicts(l)) {
          int agree = 0;
          for (int yy = -1; yy <= 1; ++yy)
            for (int xx = -1; xx <= 1; ++xx) {
              const int qx = x + xx, qy = y + yy;
              if ((xx == 0 && yy == 0) || qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
              const float lq = float(luminance(&d[3 * (qy * w + qx)]));
              if ((lq > lh) == (l > lh) && contradicts(lq)) ++agree;
            }
          if (agree >= 3) valid = false;
        }
      }
      if (valid && clip && clipped_here(i) && has_box[i]) {
        // Toward the box centre until inside (clip.glsl).
        // The prefiltered box narrowed by the raw 3x3 range of the current
        // signal where the two overlap (else the raw range), then widened to
        // p's own current value (a highlight keeps its peak); at a static
        // pixel (motion below 0.05 px) widened by its history's sigma.
        const double still = std::clamp(1.0 - std::hypot(mvx, mvy) / 0.05, 0.0, 1.0);
        const double widen = still > 0.0 ? still * history_sigma() : 0.0;
        double v[3], m = 0.0, blo[3], bhi[3];
        for (int k = 0; k < 3; ++k) {
          double rlo = d[3 * i + k], rhi = d[3 * i + k];
          for (int yy = -1; yy <= 1; ++yy)
            for (int xx = -1; xx <= 1; ++xx) {
              const int qx = x + xx, qy = y + yy;
              if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
              rlo = std::min(rlo, d[3 * (qy * w + qx) + k]);
              rhi = std::max(rhi, d[3 * (qy * w + qx) + k]);
            }
          const double nlo = std::max(lo[3 * i + k], rlo), nhi = std::min(hi[3 * i + k], rhi);
          blo[k] = std::min(nlo <= nhi ? nlo : rlo, d[3 * i + k]) - widen;
          bhi[k] = std::max(nlo <= nhi ? nhi : rhi, d[3 * i + k]) + widen;
        }
        for (int k = 0; k < 3; ++k) {
          const double centre = 0.5 * (blo[k] + bhi[k]);
          const double extent = std::max(0.5 * (bhi[k] - blo[k]), 1e-30);
          v[k] = pc[k] - centre;
          m = std::max(m, std::fabs(v[k]) / extent);
        }
        if (m > 1.0) {
          for (int k = 0; k < 3; ++k) pc[k] = std::clamp(0.5 * (blo[k] + bhi[k]) + v[k] / m, blo[k], bhi[k]);
          pm1 = luminance(pc);  // the moments restart from the clipped colour
          pm2 = pm1 * pm1;
        }
      }
      // The still mean is p's own: it goes on only where p's own previous
      // pixel passes the consistency test (valid may come from the 3x3 fallback);
      // its depth alone where either has no normal.
      const bool depth_only = !has_normal || z_[i] < 0.0;
      const bool own_same =
          depth_only ? !reset && z_[i] != 0.0 && !(std::fabs(z[i] - std::fabs(z_[i])) / (dz[i] + 0.01) > 10.0)
                     : surface_kept && z_[i] > 0.0 && !(std::fabs(z[i] - z_[i]) / (dz[i] + 0.01) > 10.0) &&
                           !(distance3(nc, &n_[3 * i]) / (dn[i] + 0.01) > 16.0);
      bool continues = own_same && std::hypot(mvx, mvy) < 0.005;
      if (keeps_still && !masked && sample_ok[i]) {
        float box = 0.0f, box2 = 0.0f, count = 0.0f, lo = 1e38f, hi = 0.0f;
        for (int yy = -1; yy <= 1; ++yy)
          for (int xx = -1; xx <= 1; ++xx) {
            const int qx = x + xx, qy = y + yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h || !fg[qy * w + qx]) continue;
            const float lq = float(luminance(&d[3 * (qy * w + qx)]));
            box += lq;
            box2 += lq * lq;
            count += 1.0f;
            lo = std::min(lo, lq);
            hi = std::max(hi, lq);
          }
        const float trimmed = count >= 3.0f ? (box - lo - hi) / (count - 2.0f) : box / count;
        const float spread =
            count >= 3.0f ? std::max(box2 - box * box / count, 0.0f) / (count - 1.0f) / (count - 2.0f) : 0.0f;
        if (!still_unchanged(ch, i, trimmed, spread, continues) && continues) continues = valid = false;
      }
      update_still(ch, i, &d[3 * i], (!masked || sampled(f.sample_count[i])) && sample_ok[i], continues);
      // Not sampled this frame: the history as reprojected (no data without one).
      if (masked && !sampled(f.sample_count[i])) {
        for (int k = 0; k < 3; ++k) colour[3 * i + k] = pc[k];
        len[i] = valid ? plen : 0.0;
        m1[i] = pm1;
        m2[i] = pm2;
      } else {
        len[i] = valid ? std::min(plen + 1.0, p_.max_history) : 1.0;
        const double ac = valid ? std::max(1.0 / len[i], p_.alpha_colour) : 1.0;
        const double am = valid ? std::max(1.0 / len[i], p_.alpha_moments) : 1.0;
        for (int k = 0; k < 3; ++k) colour[3 * i + k] = (1 - ac) * pc[k] + ac * d[3 * i + k];
        m1[i] = (1 - am) * pm1 + am * l;
        m2[i] = (1 - am) * pm2 + am * l * l;
      }
      // A still pixel whose running mean holds more than 8 samples
      // (DN_STILL_FILTER_FROM) or more than its history: the filter starts
      // from that mean, its length is their count and its moments theirs
      // (luminance mean, and mean square: the mean's square plus the sample variance).
      double still_n = 0.0;
      if (keeps_still && ch.still_n[i] > std::min(len[i], kStillFilterFrom)) {
        for (int k = 0; k < 3; ++k) colour[3 * i + k] = ch.still_mean[3 * i + k];
        len[i] = still_n = ch.still_n[i];
        const double sl = luminance(&ch.still_mean[3 * i]);
        m1[i] = sl;
        m2[i] = sl * sl + ch.still_m2[i] / std::max(ch.still_n[i] - 1.0, 1.0);
      }
      divisor[i] = variance_divisor(len[i], still_n);
    }
  ch.temporal = colour;
  // No data: a foreground pixel of length 0 (only an unsampled pixel without history has one).
  std::vector<bool> no_data(n, false);
  for (int i = 0; i < n; ++i) {
    no_data[i] = fg[i] && len[i] == 0.0;
    if (no_data[i]) hz[i] = 0.0;  // nothing reprojects from it next frame
  }

  // Pass 2: variance, of one sample or (variance_of_mean) of the temporal
  // mean: divided by variance_divisor.
  std::vector<double> var(n, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      if (!fg[i]) continue;
      if (no_data[i]) {
        var[i] = kSvgfNoData;
        continue;
      }
      if (len[i] >= 4.0) {
        // m2 - m1^2 cancels; in single precision as on the device, which
        // decides the HDR step gate and the edge-stopping of sharp pixels.
        const float f1 = float(m1[i]), f2 = float(m2[i]);
        var[i] = std::max(0.0f, f2 - f1 * f1) / divisor[i];
        continue;
      }
      if (!p_.spatial_estimate) {
        // Without the 7x7 estimate, a young pixel's own moments: in double, so
        // one sample's (or a copy's) cancel exactly, as on the device, where
        // fp32 rounding of the double moments would leave a residual that a
        // luminance weight on sqrt(variance) blows up.
        var[i] = std::max(0.0, m2[i] - m1[i] * m1[i]) / divisor[i];
        continue;
      }
      // Luminance weight relative to the darker of p and q (HDR step rule),
      // or, at an isolated bright pixel (every 3x3 foreground neighbour below
      // half its luminance: a firefly), to the brighter.
      const double l = luminance(&colour[3 * i]);
      bool isolated = true;
      for (int yy = -1; yy <= 1; ++yy)
        for (int xx = -1; xx <= 1; ++xx) {
          const int qx = x + xx, qy = y + yy;
          if ((xx == 0 && yy == 0) || qx < 0 || qy < 0 || qx >= w || qy >= h || !fg[qy * w + qx] ||
              no_data[qy * w + qx])
            continue;
          // A threshold decision: in single precision, as on the device.
          if (float(luminance(&colour[3 * (qy * w + qx)])) >= 0.5f * float(l)) isolated = false;
        }
      double s1 = 0, s2 = 0, sw = 0;
      for (int yy = -3; yy <= 3; ++yy)
        for (int xx = -3; xx <= 3; ++xx) {
          const int qx = x + xx, qy = y + yy;
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
          const int q = qy * w + qx;
          if (!fg[q] || no_data[q]) continue;  // a pixel without data takes no part
          double wt = 1.0;
          if (q != i) {
            const double dist = std::sqrt(double(xx * xx + yy * yy));
            const double wz = std::fabs(z[i] - z[q]) / (p_.phi_depth * std::max(dz[i], 1e-8) * 3.0 * dist);
            const double lq = luminance(&colour[3 * q]);
            const double relative_to = isolated ? std::max(l, lq) : std::min(l, lq);
            const double wl = std::fabs(l - lq) / (p_.phi_colour * relative_to + 1e-20);
            wt = std::exp(-wz - wl) * normal_weight(i, q);
          }
          s1 += wt * m1[q];
          s2 += wt * m2[q];
          sw += wt;
        }
      s1 /= sw;
      s2 /= sw;
      var[i] = std::max(0.0f, float(s2) - float(s1) * float(s1)) * 4.0 / len[i] /  // cancels: fp32 as on the device
               divisor[i];
    }
  ch.variance = var;

  // Pass 3: a-trous iterations over (rgb, variance). A pixel without data
  // (variance kSvgfNoData) is no tap and adds nothing of its own; it takes its
  // taps' data, or stays without.
  std::vector<double> cur(4 * n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) cur[4 * i + k] = colour[3 * i + k];
    cur[4 * i + 3] = var[i];
  }
  std::vector<double> hist_colour = colour;
  ch.atrous.assign(iterations, {});
  const int r = p_.kernel_radius;
  const double kernel[5] = {1.0 / 16, 1.0 / 4, 3.0 / 8, 1.0 / 4, 1.0 / 16};  // B3, relative to the centre's below
  const double box[3] = {0.5, 1.0, 0.5};                                     // {1/4, 1/2, 1/4} / (1/2)
  auto tap_weight = [&](int xx, int yy) {
    return r == 2 ? kernel[xx + 2] * kernel[yy + 2] / (kernel[2] * kernel[2]) : box[xx + 1] * box[yy + 1];
  };
  for (int it = 0; it < iterations; ++it) {
    const int level = p_.finest_first ? (it == 0 ? 0 : iterations - it) : it;
    const int step = 1 << level;
    std::vector<double> next(4 * n);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int i = y * w + x;
        if (!fg[i]) {
          for (int k = 0; k < 4; ++k) next[4 * i + k] = cur[4 * i + k];
          continue;
        }
        const bool has_data = cur[4 * i + 3] != kSvgfNoData;
        // 3x3 Gaussian of the variance over the neighbours with data whose own
        // noise explains their luminance step to p (HDR step rule, 3 sigmas).
        const double l = luminance(&cur[4 * i]);
        double gv = 0, gw = 0;
        for (int yy = -1; yy <= 1; ++yy)
          for (int xx = -1; xx <= 1; ++xx) {
            const int qx = x + xx, qy = y + yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
            const double* cq = &cur[4 * (qy * w + qx)];
            if (cq[3] == kSvgfNoData) continue;
            // A threshold decision: in single precision, as on the device.
            if (!(xx == 0 && yy == 0) &&
                !(std::fabs(float(l) - float(luminance(cq))) <= 3.0f * std::sqrt(float(cq[3]))))
              continue;
            const double k = (xx == 0 ? 0.5 : 0.25) * (yy == 0 ? 0.5 : 0.25);
            gv += k * cq[3];
            gw += k;
          }
        const double g = gw > 0.0 ? gv / gw : 0.0;
        double ramp = p_.luminance_ramp ? 8.0 - std::min(7.0, std::max(len[i] - 1.0, 0.0)) : 1.0;
        // Luminance weight |l_p - l_q| / bandwidth; none for p without data or
        // younger than luminance_min_age (its variance is unusable).
        const bool luminance_on = has_data && !(len[i] < p_.luminance_min_age);
        // Age-gated: the weight comes in over luminance_ramp_in samples, bandwidth x 2^r, ..., 2.
        if (p_.luminance_min_age > 0.0)
          ramp *= std::exp2(std::clamp(p_.luminance_min_age + p_.luminance_ramp_in - len[i], 0.0, p_.luminance_ramp_in));
        const double bandwidth = p_.luminance_form == 0 ? p_.phi_colour * ramp * std::sqrt(g + 1e-20)
                                                        : ramp * (p_.sigma_luminance * g + p_.epsilon_luminance);
        double sc[3] = {0, 0, 0}, sv = 0, sw = 0;
        for (int yy = -r; yy <= r; ++yy)
          for (int xx = -r; xx <= r; ++xx) {
            const int qx = x + step * xx, qy = y + step * yy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
            const int q = qy * w + qx;
            if (!fg[q] || cur[4 * q + 3] == kSvgfNoData) continue;
            double wt = 1.0;
            if (q != i) {
              const double dist = step * std::sqrt(double(xx * xx + yy * yy));
              const double wz = std::fabs(z[i] - z[q]) / (p_.phi_depth * std::max(dz[i], 1e-8) * dist);
              const double wl = luminance_on ? std::fabs(l - luminance(&cur[4 * q])) / bandwidth : 0.0;
              wt = tap_weight(xx, yy) * std::exp(-wz - wl) * normal_weight(i, q);
            }
            for (int k = 0; k < 3; ++k) sc[k] += wt * cur[4 * q + k];
            sv += wt * wt * cur[4 * q + 3];
            sw += wt;
          }
        if (!(sw > 0.0)) {  // neither p nor a tap has data
          for (int k = 0; k < 3; ++k) next[4 * i + k] = 0.0;
          next[4 * i + 3] = kSvgfNoData;
          // The last iteration's display fill: the nearest ring of foreground
          // pixels with a normal and data.
          double fill[3];
          if (masked && it + 1 == iterations && ring_fill(x, y, [&](int q, double* v) {
                for (int k = 0; k < 3; ++k) v[k] = cur[4 * q + k];
                return fg[q] && has_normal_at(q) && cur[4 * q + 3] != kSvgfNoData;
              }, fill)) {
            for (int k = 0; k < 3; ++k) next[4 * i + k] = fill[k];
            next[4 * i + 3] = 0.0;
          }
          continue;
        }
        for (int k = 0; k < 3; ++k) next[4 * i + k] = sc[k] / sw;
        // Without propagation p keeps its own variance (0 where it had none: the device's).
        next[4 * i + 3] = p_.propagate_variance ? sv / (sw * sw) : (has_data ? cur[4 * i + 3] : 0.0);
      }
    cur = std::move(next);
    ch.atrous[it] = cur;
    // Feedback: the history colour changes only where this frame has a sample
    // and, with the age gate, only once the pixel is old enough for the
    // luminance weight (a younger one keeps its unfiltered accumulation).
    if (it == tap)
      for (int i = 0; i < n; ++i)
        if ((!masked || sampled(f.sample_count[i])) && !(p_.luminance_min_age > 0.0 && len[i] < p_.luminance_min_age))
          for (int k = 0; k < 3; ++k) hist_colour[3 * i + k] = cur[4 * i + k];
  }

  ch.colour = std::move(hist_colour);
  ch.length = std::move(len);
  ch.m1 = std::move(m1);
  ch.m2 = std::move(m2);
  return cur;
  };

  // Emission, sanitized like radiance; it is added back after filtering.
  const std::vector<double> e = f.emission.empty() ? std::vector<double>(3 * n, 0.0) : sanitize(f.emission);
  // The specular factor (svgf-fb's F_beta), guarded like albedo.
  std::vector<double> sf(3 * n, 1.0);
  if (!f.specular_factor.empty())
    for (int i = 0; i < 3 * n; ++i) {
      sf[i] = guarded(f.specular_factor[i]);
    }
  std::vector<double> cur, spec, raw;
  if (split) {
    const std::vector<double> one(3 * n, 1.0);
    cur = filter(chains_[0], sanitize(f.diffuse), f.diffuse_lighting ? one : a, false, valid_samples(f.diffuse));
    spec = filter(chains_[1], sanitize(f.specular), f.specular_lighting ? one : sf, true, valid_samples(f.specular));
  } else {
    // Radiance includes what the primary hit emits: filter radiance - emission (>= 0).
    std::vector<double> c = sanitize(f.radiance);
    for (int i = 0; i < 3 * n; ++i) c[i] = std::max(c[i] - e[i], 0.0);
    cur = filter(chains_[0], c, a, true, valid_samples(f.radiance));
    raw = std::move(c);
  }

  // Pass 4a (harm_guard g > 0, with a-trous): each chain's filtered value f
  // moves back toward its target t where the luminance of f - t exceeds the
  // allowed deviation a: t + (f - t) (a / Y(f - t))^2; only where the
  // history length is at least 4 (v from the pixel's own moments). The
  // moving target is the temporal mean m of variance v, a = g sqrt(v). With
  // converge_still k, where the still running mean holds n >= 4 samples, the
  // still target is that mean, a = k sqrt(s2 / n), s2 the larger of v
  // variance_divisor(length, n) and the mean over the 3x3 pixels whose still
  // mean holds n >= 2 of M2 / (n - 1),
  // factor (a / Y(f - t))^3, and the result is mix(moving, still, w) with
  // w = min((n - 3) / 4, 1). Where the still mean holds n >= 2 samples, the
  // moving target's a = g sqrt(s2 / variance_divisor(length, n)), and while
  // the history length is below 8 both a^2 are multiplied by (8 / length)^2.
  // guard_target gives the moving target, the still one and w (0: not
  // still); false where pixel i has no data.
  struct Target {
    double rgb[3], allowed;
  };
  auto guard_target = [&](const Chain& ch, int i, Target& moving, Target& still, double& w) {
    const double v = ch.variance[i];
    w = 0.0;
    if (!(v >= 0.0)) return false;
    for (int k = 0; k < 3; ++k) moving.rgb[k] = ch.temporal[3 * i + k];
    moving.allowed = p_.harm_guard * p_.harm_guard * v;
    const double n_still = keeps_still ? ch.still_n[i] : 0.0;
    if (!(n_still >= 2.0)) return true;
    double sum = 0.0, count = 0.0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = i % w_ + dx, y = i / w_ + dy, q = y * w_ + x;
        if (x < 0 || y < 0 || x >= w_ || y >= h_ || !(ch.still_n[q] >= 2.0)) continue;
        sum += ch.still_m2[q] / (ch.still_n[q] - 1.0);
        count += 1.0;
      }
    const double divisor = variance_divisor(ch.length[i], n_still);
    const double s2 = std::max(v * divisor, sum / std::max(count, 1.0));
    const double widening = std::pow(std::max(1.0, kGuardSureLength / ch.length[i]), 2.0);
    moving.allowed = p_.harm_guard * p_.harm_guard * s2 / divisor * widening;
    if (n_still >= kStillMinSamples) {
      w = std::min((n_still - kStillMinSamples + 1.0) / kStillRamp, 1.0);
      for (int k = 0; k < 3; ++k) still.rgb[k] = ch.still_mean[3 * i + k];
      still.allowed = p_.converge_still * p_.converge_still * s2 / n_still * widening;
    }
    return true;
  };
  auto guarded_toward = [](const double* f, const Target& t, bool cubic, double* out) {
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = f[k] - t.rgb[k];
    const double dl = luminance(d), r = t.allowed / (dl * dl);
    for (int k = 0; k < 3; ++k) out[k] = dl * dl > t.allowed ? t.rgb[k] + d[k] * (cubic ? r * std::sqrt(r) : r) : f[k];
  };
  auto guard = [&](std::vector<double>& filtered, const Chain& ch) {
    if (!(p_.harm_guard > 0.0) || iterations == 0) return;
    for (int i = 0; i < n; ++i) {
      Target moving, still;
      double w;
      if (!guard_target(ch, i, moving, still, w) || ch.length[i] < 4.0) continue;  // no data, or a variance not the pixel's own
      double m[3], s[3];
      guarded_toward(&filtered[4 * i], moving, false, m);
      if (w > 0.0) guarded_toward(&filtered[4 * i], still, true, s);
      for (int k = 0; k < 3; ++k) filtered[4 * i + k] = w > 0.0 ? m[k] + (s[k] - m[k]) * w : m[k];
    }
  };
  // What a kept still pixel blends toward: its still running mean once that
  // holds a sample, else its temporal mean (unchanged where it has no data).
  auto guard_mean = [&](const Chain& ch, int i, double* t) {
    Target moving, still;
    double w;
    if (!guard_target(ch, i, moving, still, w)) return;
    const bool has_mean = keeps_still && ch.still_n[i] >= 1.0;
    for (int k = 0; k < 3; ++k) t[k] = has_mean ? ch.still_mean[3 * i + k] : moving.rgb[k];
  };
  guard(cur, chains_[0]);
  if (split) guard(spec, chains_[1]);
  // Pass 4b (keep_unexplained; with a validity mask only at sampled pixels):
  // a pixel whose (diffuse) albedo is below 1e-3 in every component or above
  // 1.5 in one (or not finite: not a reflectance) shows its current radiance
  // - emission (split: diffuse + specular radiance), blended by its
  // stillness toward its unfiltered temporal mean (remodulated), then +
  // emission.
  auto keeping = [&](int i) { return p_.keep_unexplained && (!masked || sampled(f.sample_count[i])); };
  std::vector<bool> kept(n, false);
  for (int i = 0; i < n; ++i) {
    const double m = largest_f32(f.albedo, i);
    kept[i] = keeping(i) && !(m >= static_cast<double>(1e-3f) && m <= 1.5);
  }
  std::vector<double> dsan, ssan;
  if (split) {
    dsan = sanitize(f.diffuse);
    ssan = sanitize(f.specular);
  }
  // Where still (and with the guard's buffer: harm_guard, a-trous), toward
  // the guard's targets (guard_mean); not where the albedo is above 1.5 (a
  // frame's own, which the means of other frames' samples are not).
  auto stillness = [&](int i) {
    bool own = p_.harm_guard > 0.0 && iterations > 0 && chains_[0].variance[i] >= 0.0 &&
               !(largest_f32(f.albedo, i) >= static_cast<double>(1e-3f));
    if (split) own = own && chains_[1].variance[i] >= 0.0;
    const double mx = f.motion[2 * i], my = f.motion[2 * i + 1];
    return own && usable_motion(mx, my) ? std::clamp(1.0 - std::hypot(mx, my) / 0.05, 0.0, 1.0) : 0.0;
  };

  // keep_unexplained, split: a pixel whose specular factor is below 1e-3 in
  // every component (or not finite) has no specular lobe, and its specular
  // term is what it was sent, not what the filter brought in.
  auto no_lobe = [&](int i) {
    if (!split || !keeping(i) || f.specular_factor.empty()) return false;
    return !(largest_f32(f.specular_factor, i) >= static_cast<double>(1e-3f));
  };

  // Emission added back (with converge_still): where the pixel is still
  // (usable motion below 0.005 px, no reset) the running mean of its own
  // emission samples, restarted when a sample's luminance is beyond 6
  // standard deviations of the mean's samples (M2 / (n - 1) (1 + 1 / n),
  // from 8 samples; plus (1e-3 max(Y, Y_mean))^2) two frames in a row (the
  // first failure merges into the mean, not M2, and marks the pixel
  // suspect). A sample the
  // sanitizer changed is not counted. Elsewhere (moving or background
  // pixels, which keep no mean) the current emission.
  std::vector<double> added = e;
  if (keeps_still && !f.emission.empty()) {
    if (emission_n_.empty()) {
      emission_mean_.assign(3 * n, 0.0);
      emission_n_.assign(n, 0.0);
      emission_m2_.assign(n, 0.0);
      emission_suspect_.assign(n, false);
    }
    const std::vector<bool> valid = valid_samples(std::vector<double>(f.emission.begin(), f.emission.end()));
    for (int i = 0; i < n; ++i) {
      const double mx = f.motion[2 * i], my = f.motion[2 * i + 1];
      const bool background = !foreground(f.depth[i]);
      if (background || reset || !usable_motion(mx, my) || !(std::hypot(mx, my) < 0.005)) {
        emission_n_[i] = 0.0;
        emission_m2_[i] = 0.0;
        emission_suspect_[i] = false;
      }
      if (background) continue;
      double* mean = &emission_mean_[3 * i];
      if (valid[i]) {
        const double l = luminance(&e[3 * i]), lm = luminance(mean), sn = emission_n_[i];
        bool fail = false;
        if (sn >= 8.0) {
          const double d = l - lm, bound = 1e-3 * std::max(l, lm);
          fail = d * d > 36.0 * emission_m2_[i] / (sn - 1.0) * (1.0 + 1.0 / sn) + bound * bound;
        }
        if (sn > 0.0 && !(fail && emission_suspect_[i])) {
          const double k = std::min(sn + 1.0, 65536.0);
          for (int c = 0; c < 3; ++c) mean[c] += (e[3 * i + c] - mean[c]) / k;
          if (!fail) emission_m2_[i] += (l - lm) * (l - luminance(mean));
          emission_n_[i] = k;
          emission_suspect_[i] = fail;
        } else {
          for (int c = 0; c < 3; ++c) mean[c] = e[3 * i + c];
          emission_n_[i] = 1.0;
          emission_m2_[i] = 0.0;
          emission_suspect_[i] = false;
        }
      }
      if (emission_n_[i] > 0.0)
        for (int c = 0; c < 3; ++c) added[3 * i + c] = mean[c];
    }
  }

  // Pass 4: remodulate (+ specular, + emission).
  std::vector<double> out(3 * n);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const int j = 3 * i + k;
      if (!kept[i]) {
        double s = 0.0;
        if (split) s = no_lobe(i) ? ssan[j] * (f.specular_lighting ? sf[j] : 1.0) : spec[4 * i + k] * sf[j];
        out[j] = cur[4 * i + k] * a[j] + s + added[j];
        continue;
      }
      const double s = stillness(i);
      double t[3] = {0.0, 0.0, 0.0}, t2[3] = {0.0, 0.0, 0.0};
      guard_mean(chains_[0], i, t);
      double now, mean = t[k] * a[j];
      if (split) {
        now = dsan[j] * (f.diffuse_lighting ? a[j] : 1.0) + ssan[j] * (f.specular_lighting ? sf[j] : 1.0);
        guard_mean(chains_[1], i, t2);
        mean += t2[k] * sf[j];
      } else {
        now = raw[j];
      }
      out[j] = now * (1.0 - s) + mean * s + added[j];
    }

  remodulated_ = out;
  // Pass 5 (taa_alpha or taa_static_alpha > 0): previous final output at
  // p + mv (bilinear over the taps inside the image, renormalized, at least
  // 1e-3 of weight) for a foreground pixel without reset, clamped per channel
  // to the min/max of the current colour over the 3x3 foreground neighbours
  // within 10 depth gradients of p (and not kept), out = mix(clamped, current, a):
  // a = taa_alpha (1 when 0) where |mv| >= 0.05 px, falling linearly to
  // taa_static_alpha at |mv| = 0 when that is smaller, at least 0.5 where
  // the still mean holds 4 or more samples (converge_still); no blend when
  // a = 1 or at a pixel kept as rendered. display_lag: a state s per pixel, -1 while chain 0's length is below
  // luminance_min_age, else 0 without that blend, else (1 where the previous
  // state, at the bilinear tap of the largest weight (the first of equals),
  // is below 0, else that state x (1 - a)) x the stillness; the clamped value
  // moves toward the unclamped one by max(s, 0).
  if (p_.taa_alpha > 0.0 || p_.taa_static_alpha > 0.0) {
    const std::vector<double>& cur_c = remodulated_;
    std::vector<double> lag(n, 0.0);
    if (lag_.empty()) lag_.assign(n, 0.0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int i = y * w + x;
        // A pixel kept as rendered blends only where it is still (taa_alpha 1).
        const double moving = p_.taa_alpha > 0.0 && !kept[i] ? p_.taa_alpha : 1.0;
        const bool young = p_.display_lag && chains_[0].length[i] < p_.luminance_min_age;
        if (young) lag[i] = -1.0;
        if (kept[i] && keeps_still) continue;  // it shows its still running mean as it is
        const double mvx = f.motion[2 * i], mvy = f.motion[2 * i + 1];
        if (reset || !fg[i] || !usable_motion(mvx, mvy)) continue;
        const double fx = x + mvx, fy = y + mvy;  // previous position - 0.5
        if (!(fx > -1.0 && fy > -1.0 && fx < w && fy < h)) continue;
        const double bx = std::floor(fx), by = std::floor(fy), tx = fx - bx, ty = fy - by;
        const int ox = static_cast<int>(bx), oy = static_cast<int>(by);
        double s[3] = {0.0, 0.0, 0.0}, sw = 0.0, heaviest = 0.0, prev_lag = 0.0;
        for (int k = 0; k < 4; ++k) {
          const int qx = ox + (k & 1), qy = oy + (k >> 1);
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
          const double wk = ((k & 1) ? tx : 1.0 - tx) * ((k >> 1) ? ty : 1.0 - ty);
          for (int c = 0; c < 3; ++c) s[c] += wk * taa_[3 * (qy * w + qx) + c];
          sw += wk;
          if (wk > heaviest) {
            heaviest = wk;
            prev_lag = lag_[qy * w + qx];
          }
        }
        if (!(sw >= static_cast<double>(1e-3f))) continue;
        const double still = std::clamp(1.0 - std::hypot(mvx, mvy) / 0.05, 0.0, 1.0);
        double a = p_.taa_static_alpha > 0.0 && p_.taa_static_alpha < moving
                       ? moving + (p_.taa_static_alpha - moving) * still
                       : moving;
        if (keeps_still && chains_[0].still_n[i] >= kStillMinSamples) a = std::max(a, 0.5);  // the guard's target
        if (a >= 1.0) continue;
        if (p_.display_lag && !young) lag[i] = (prev_lag < 0.0 ? 1.0 : prev_lag * (1.0 - a)) * still;
        const double give = std::max(lag[i], 0.0);
        for (int c = 0; c < 3; ++c) {
          double lo = cur_c[3 * i + c], hi = lo;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int qx = x + dx, qy = y + dy;
              if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
              if ((dx != 0 || dy != 0) && kept[qy * w + qx]) continue;  // what it shows is not the surface's
              const int q = qy * w + qx;
              if (!fg[q] || std::fabs(z[i] - z[q]) / (dz[i] + 0.01) > 10.0) continue;  // another surface
              lo = std::min(lo, cur_c[3 * (qy * w + qx) + c]);
              hi = std::max(hi, cur_c[3 * (qy * w + qx) + c]);
            }
          const double clamped = std::clamp(s[c] / sw, lo, hi);
          const double prev = clamped + (s[c] / sw - clamped) * give;
          out[3 * i + c] = prev * (1.0 - a) + cur_c[3 * i + c] * a;
        }
      }
    taa_ = out;
    lag_ = std::move(lag);
  }

  z_ = std::move(hz);
  n_ = std::move(hn);
  has_history_ = true;
  return out;
}

}  // namespace dn::test
