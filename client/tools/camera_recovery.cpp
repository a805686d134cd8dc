#include "camera_recovery.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>

#include "camera_file.hpp"
#include "frame_source.hpp"

namespace dn::cli {

namespace {


std::string num(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// Symmetric eigen-decomposition by cyclic Jacobi rotations (n <= 12).
// a: n*n row-major, destroyed; values ascending, vectors as columns of v.
void jacobi_eigen(std::vector<double> a, size_t n, std::vector<double>& values, std::vector<double>& v) {
  v.assign(n * n, 0.0);
  for (size_t i = 0; i < n; ++i) v[i * n + i] = 1.0;
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0, total = 0;
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) (i == j ? total : off) += a[i * n + j] * a[i * n + j];
    if (off <= 1e-30 * (total + off) || off == 0.0) break;
    for (size_t p = 0; p < n; ++p)
      for (size_t q = p + 1; q < n; ++q) {
        const double apq = a[p * n + q];
        if (apq == 0.0) continue;
        const double theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (size_t k = 0; k < n; ++k) {  // columns p, q
          const double akp = a[k * n + p], akq = a[k * n + q];
          a[k * n + p] = c * akp - s * akq;
          a[k * n + q] = s * akp + c * akq;
        }
        for (size_t k = 0; k < n; ++k) {  // rows p, q
          const double apk = a[p * n + k], aqk = a[q * n + k];
          a[p * n + k] = c * apk - s * aqk;
          a[q * n + k] = s * apk + c * aqk;
        }
        for (size_t k = 0; k < n; ++k) {
          const double vkp = v[k * n + p], vkq = v[k * n + q];
          v[k * n + p] = c * vkp - s * vkq;
          v[k * n + q] = s * vkp + c * vkq;
        }
      }
  }
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) { return a[x * n + x] < a[y * n + y]; });
  values.resize(n);
  std::vector<double> sorted(n * n);
  for (size_t j = 0; j < n; ++j) {
    values[j] = a[order[j] * n + order[j]];
    for (size_t k = 0; k < n; ++k) sorted[k * n + j] = v[k * n + order[j]];
  }
  v = std::move(sorted);
}

// Solves a x = b (n x n, row-major) by Gaussian elimination with partial pivoting.
bool solve(std::vector<double> a, std::vector<double> b, size_t n, std::vector<double>& x) {
  for (size_t c = 0; c < n; ++c) {
    size_t piv = c;
    for (size_t r = c + 1; r < n; ++r)
      if (std::fabs(a[r * n + c]) > std::fabs(a[piv * n + c])) piv = r;
    if (!(std::fabs(a[piv * n + c]) > 0)) return false;
    if (piv != c) {
      for (size_t k = 0; k < n; ++k) std::swap(a[c * n + k], a[piv * n + k]);
      std::swap(b[c], b[piv]);
    }
    for (size_t r = c + 1; r < n; ++r) {
      const double f = a[r * n + c] / a[c * n + c];
      for (size_t k = c; k < n; ++k) a[r * n + k] -= f * a[c * n + k];
      b[r] -= f * b[c];
    }
  }
  x.assign(n, 0.0);
  for (size_t r = n; r-- > 0;) {
    double s = b[r];
    for (size_t k = r + 1; k < n; ++k) s -= a[r * n + k] * x[k];
    x[r] = s / a[r * n + r];
  }
  return true;
}

struct Pair {
  double X[3];  // world (normalised during the fit)
  double u[2];  // pixel (normalised during the fit)
};

using P34 = std::array<double, 12>;  // row-major 3x4

bool project(const P34& p, const double X[3], double out[2]) {
  const double w = p[8] * X[0] + p[9] * X[1] + p[10] * X[2] + p[11];
  if (!(std::fabs(w) > 0)) return false;
  out[0] = (p[0] * X[0] + p[1] * X[1] + p[2] * X[2] + p[3]) / w;
  out[1] = (p[4] * X[0] + p[5] * X[1] + p[6] * X[2] + p[7]) / w;
  return true;
}

double residual(const P34& p, const Pair& q) {
  double u[2];
  if (!project(p, q.X, u)) return INFINITY;
  return std::hypot(u[0] - q.u[0], u[1] - q.u[1]);
}

void normalise(P34& p) {
  double s = 0;
  for (double v : p) s += v * v;
  s = std::sqrt(s);
  for (double& v : p) v /= s;
}

// Normalised DLT: the unit P minimising the algebraic error, from the 12x12 normal matrix.
P34 dlt(const std::vector<Pair>& pts, double& gap) {
  std::vector<double> ata(144, 0.0);
  for (const Pair& q : pts) {
    const double X[4] = {q.X[0], q.X[1], q.X[2], 1.0};
    double r1[12] = {}, r2[12] = {};
    for (int k = 0; k < 4; ++k) {
      r1[k] = X[k];
      r1[8 + k] = -q.u[0] * X[k];
      r2[4 + k] = X[k];
      r2[8 + k] = -q.u[1] * X[k];
    }
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j) ata[size_t(i * 12 + j)] += r1[i] * r1[j] + r2[i] * r2[j];
  }
  std::vector<double> values, vectors;
  jacobi_eigen(ata, 12, values, vectors);
  gap = values[11] > 0 ? values[1] / values[11] : 0.0;
  P34 p;
  for (size_t k = 0; k < 12; ++k) p[k] = vectors[k * 12 + 0];
  normalise(p);
  return p;
}

// Levenberg-Marquardt on the reprojection error (in the normalised frame, a
// uniform scale of pixels). The scale of P is a gauge freedom; Marquardt's
// diagonal damping keeps the step finite and P is renormalised after each.
P34 refine(P34 p, const std::vector<Pair>& pts) {
  auto cost = [&](const P34& c) {
    double s = 0;
    for (const Pair& q : pts) {
      const double r = residual(c, q);
      s += r * r;
    }
    return s;
  };
  double current = cost(p), lambda = 1e-3;
  for (int it = 0; it < 30; ++it) {
    std::vector<double> jtj(144, 0.0), jtr(12, 0.0);
    for (const Pair& q : pts) {
      const double X[4] = {q.X[0], q.X[1], q.X[2], 1.0};
      const double w = p[8] * X[0] + p[9] * X[1] + p[10] * X[2] + p[11];
      const double a = p[0] * X[0] + p[1] * X[1] + p[2] * X[2] + p[3];
      const double b = p[4] * X[0] + p[5] * X[1] + p[6] * X[2] + p[7];
      const double u = a / w, v = b / w;
      double ju[12] = {}, jv[12] = {};
      for (int k = 0; k < 4; ++k) {
        ju[k] = X[k] / w;
        ju[8 + k] = -u * X[k] / w;
        jv[4 + k] = X[k] / w;
        jv[8 + k] = -v * X[k] / w;
      }
      const double ru = q.u[0] - u, rv = q.u[1] - v;
      for (int i = 0; i < 12; ++i) {
        jtr[size_t(i)] += ju[i] * ru + jv[i] * rv;
        for (int j = 0; j < 12; ++j) jtj[size_t(i * 12 + j)] += ju[i] * ju[j] + jv[i] * jv[j];
      }
    }
    bool improved = false;
    for (int tries = 0; tries < 8 && !improved; ++tries) {
      std::vector<double> a = jtj, delta;
      for (size_t i = 0; i < 12; ++i) a[i * 13] += lambda * (jtj[i * 13] + 1e-12);
      if (!solve(a, jtr, 12, delta)) {
        lambda *= 10;
        continue;
      }
      P34 next = p;
      for (size_t i = 0; i < 12; ++i) next[i] += delta[i];
      normalise(next);
      const double c = cost(next);
      if (c < current) {
        const double gain = current - c;
        p = next;
        improved = true;
        lambda = std::max(lambda * 0.1, 1e-12);
        const bool converged = gain <= 1e-14 * current;
        current = c;
        if (converged) return p;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  return p;
}

std::array<double, 3> mat3_vec(const double m[9], const double v[3]) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

bool invert3(const double m[9], double out[9], double& det) {
  det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
  if (!(std::fabs(det) > 0)) return false;
  out[0] = (m[4] * m[8] - m[5] * m[7]) / det;
  out[1] = (m[2] * m[7] - m[1] * m[8]) / det;
  out[2] = (m[1] * m[5] - m[2] * m[4]) / det;
  out[3] = (m[5] * m[6] - m[3] * m[8]) / det;
  out[4] = (m[0] * m[8] - m[2] * m[6]) / det;
  out[5] = (m[2] * m[3] - m[0] * m[5]) / det;
  out[6] = (m[3] * m[7] - m[4] * m[6]) / det;
  out[7] = (m[1] * m[6] - m[0] * m[7]) / det;
  out[8] = (m[0] * m[4] - m[1] * m[3]) / det;
  return true;
}

}  // namespace

RecoveredCamera recover_camera(std::span<const float> positions, int width, int height, std::span<const float> depth,
                               const CameraRecoveryOptions& options) {
  if (width <= 0 || height <= 0 || positions.size() < size_t(width) * size_t(height) * 3)
    throw CameraRecoveryError("the Position plane is smaller than " + std::to_string(width) + "x" +
                              std::to_string(height) + "x3 floats");
  const bool use_depth = depth.size() >= size_t(width) * size_t(height);

  // ---- a stratified grid of foreground pixels ----
  size_t stride = 1;
  const size_t cap = std::max<size_t>(options.max_samples, 1);
  while (((size_t(width) + stride - 1) / stride) * ((size_t(height) + stride - 1) / stride) > cap) ++stride;
  std::vector<Pair> all;
  for (size_t y = stride / 2; y < size_t(height); y += stride)
    for (size_t x = stride / 2; x < size_t(width); x += stride) {
      const size_t i = y * size_t(width) + x;
      const float* p = &positions[3 * i];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
      if (p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f) continue;
      if (use_depth && !(std::isfinite(depth[i]) && depth[i] > 0.0f)) continue;
      all.push_back({{p[0], p[1], p[2]}, {double(x) + 0.5, double(y) + 0.5}});
    }
  if (all.size() < options.min_points)
    throw CameraRecoveryError("only " + std::to_string(all.size()) + " usable pixels in the Position pass (" +
                              std::to_string(options.min_points) +
                              " needed; background pixels are non-finite, all-zero or have no depth)");

  // ---- Hartley normalisation ----
  double c3[3] = {0, 0, 0}, c2[2] = {0, 0};
  for (const Pair& q : all) {
    for (int k = 0; k < 3; ++k) c3[k] += q.X[k];
    for (int k = 0; k < 2; ++k) c2[k] += q.u[k];
  }
  for (double& v : c3) v /= double(all.size());
  for (double& v : c2) v /= double(all.size());
  double d3 = 0, d2 = 0;
  for (const Pair& q : all) {
    d3 += std::sqrt((q.X[0] - c3[0]) * (q.X[0] - c3[0]) + (q.X[1] - c3[1]) * (q.X[1] - c3[1]) +
                    (q.X[2] - c3[2]) * (q.X[2] - c3[2]));
    d2 += std::hypot(q.u[0] - c2[0], q.u[1] - c2[1]);
  }
  d3 /= double(all.size());
  d2 /= double(all.size());
  if (!(d3 > 0) || !(d2 > 0))
    throw CameraRecoveryError("the usable pixels of the Position pass all hold the same point");
  const double s3 = std::sqrt(3.0) / d3, s2 = std::sqrt(2.0) / d2;
  std::vector<Pair> norm = all;
  for (Pair& q : norm) {
    for (int k = 0; k < 3; ++k) q.X[k] = (q.X[k] - c3[k]) * s3;
    for (int k = 0; k < 2; ++k) q.u[k] = (q.u[k] - c2[k]) * s2;
  }

  // ---- coplanar (or collinear) points cannot determine P ----
  {
    std::vector<double> cov(9, 0.0);
    for (const Pair& q : norm)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) cov[size_t(i * 3 + j)] += q.X[i] * q.X[j];
    std::vector<double> ev, evec;
    jacobi_eigen(cov, 3, ev, evec);
    const double thin = std::sqrt(std::max(ev[0], 0.0)), wide = std::sqrt(std::max(ev[2], 1e-300));
    if (thin < options.planarity * wide)
      throw CameraRecoveryError("the " + std::to_string(all.size()) +
                                " usable pixels of the Position pass lie on one plane (thickness " +
                                num("%.2g", thin / wide) +
                                " of their extent): a pinhole camera cannot be recovered from a single plane "
                                "(e.g. a frame showing only the floor)");
  }

  // ---- fit, dropping outliers (silhouette pixels mix two surfaces) ----
  std::vector<char> inlier(all.size(), 1);
  P34 pn{};
  double gap = 0;
  for (int round = 0; round < 4; ++round) {
    std::vector<Pair> use;
    for (size_t i = 0; i < norm.size(); ++i)
      if (inlier[i]) use.push_back(norm[i]);
    if (use.size() < options.min_points)
      throw CameraRecoveryError("only " + std::to_string(use.size()) +
                                " pixels of the Position pass agree with one pinhole camera");
    pn = refine(dlt(use, gap), use);
    if (round == 0 && gap < 1e-12)
      throw CameraRecoveryError("the usable pixels of the Position pass are degenerate (they do not determine a "
                                "3x4 projection)");
    std::vector<double> r(all.size());
    for (size_t i = 0; i < norm.size(); ++i) r[i] = residual(pn, norm[i]) / s2;  // pixels
    std::vector<double> sorted = r;
    std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
    const double median = sorted[sorted.size() / 2];
    const double threshold = std::max(0.5, 4.0 * median);
    bool changed = false;
    for (size_t i = 0; i < r.size(); ++i) {
      const char keep = r[i] <= threshold ? 1 : 0;
      changed |= keep != inlier[i];
      inlier[i] = keep;
    }
    if (!changed) break;
  }

  // ---- back to pixels: P = T2^-1 Pn T3 ----
  P34 p{};
  {
    double t3[16] = {s3, 0, 0, -s3 * c3[0], 0, s3, 0, -s3 * c3[1], 0, 0, s3, -s3 * c3[2], 0, 0, 0, 1};
    double t2inv[9] = {1 / s2, 0, c2[0], 0, 1 / s2, c2[1], 0, 0, 1};
    double tmp[12];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += pn[size_t(r * 4 + k)] * t3[k * 4 + c];
        tmp[r * 4 + c] = s;
      }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        double s = 0;
        for (int k = 0; k < 3; ++k) s += t2inv[r * 3 + k] * tmp[k * 4 + c];
        p[size_t(r * 4 + c)] = s;
      }
  }
  // Scale so that the third row's direction is a unit vector, sign so the points are in front (w = depth > 0).
  const double m3 = std::sqrt(p[8] * p[8] + p[9] * p[9] + p[10] * p[10]);
  std::vector<double> w;
  for (size_t i = 0; i < all.size(); ++i)
    if (inlier[i]) w.push_back(p[8] * all[i].X[0] + p[9] * all[i].X[1] + p[10] * all[i].X[2] + p[11]);
  std::vector<double> wsorted = w;
  std::sort(wsorted.begin(), wsorted.end());
  const double sign = wsorted[wsorted.size() / 2] < 0 ? -1.0 : 1.0;
  const double wmin = sign > 0 ? wsorted.front() : -wsorted.back(), wmax = sign > 0 ? wsorted.back() : -wsorted.front();
  const std::string pinhole_hint =
      " (a panoramic, fisheye or orthographic camera? In Blender, Camera → Lens → Type must be Perspective)";
  if (!(m3 > 0) || !(wmin > 0) || wmax < wmin * (1.0 + 1e-4))
    throw CameraRecoveryError("the Position pass fits a camera at infinity or points on both sides of it: not a "
                              "perspective camera" + pinhole_hint);
  for (double& v : p) v *= sign / m3;

  RecoveredCamera out;
  out.pixel_projection = p;
  double sum2 = 0, maxr = 0, dmin = INFINITY, dmax = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    if (!inlier[i]) {
      ++out.rejected;
      continue;
    }
    const double r = residual(p, all[i]);
    sum2 += r * r;
    maxr = std::max(maxr, r);
    const double d = p[8] * all[i].X[0] + p[9] * all[i].X[1] + p[10] * all[i].X[2] + p[11];
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
    ++out.points;
  }
  out.rms_px = std::sqrt(sum2 / double(out.points));
  out.max_px = maxr;
  if (out.rms_px > options.max_rms_px || double(out.rejected) > options.max_outlier_fraction * double(all.size()))
    throw CameraRecoveryError("the Position pass is not consistent with a pinhole camera: RMS reprojection residual " +
                              num("%.3g", out.rms_px) + " px (limit " + num("%g", options.max_rms_px) + "), " +
                              std::to_string(out.rejected) + " of " + std::to_string(all.size()) +
                              " pixels rejected as outliers" + pinhole_hint);

  // ---- decomposition: M = K R, K upper triangular with a positive diagonal ----
  const double M[9] = {p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]};
  double A[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A[i * 3 + j] = M[i * 3] * M[j * 3] + M[i * 3 + 1] * M[j * 3 + 1] + M[i * 3 + 2] * M[j * 3 + 2];
  const double kf = std::sqrt(A[8]);  // 1
  const double ke = A[5] / kf, kc = A[2] / kf;
  const double kd = std::sqrt(std::max(A[4] - ke * ke, 0.0));
  const double kb = (A[1] - kc * ke) / kd;
  const double ka = std::sqrt(std::max(A[0] - kb * kb - kc * kc, 0.0));
  const double K[9] = {ka, kb, kc, 0, kd, ke, 0, 0, kf};
  double Kinv[9], Minv[9], detK = 0, detM = 0;
  if (!(ka > 0) || !(kd > 0) || !invert3(K, Kinv, detK) || !invert3(M, Minv, detM))
    throw CameraRecoveryError("the fitted projection is singular: not a perspective camera" + pinhole_hint);
  if (detM < 0)
    throw CameraRecoveryError("the fitted camera is mirrored (left-handed image axes)");
  double R[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R[i * 3 + j] = Kinv[i * 3] * M[j] + Kinv[i * 3 + 1] * M[3 + j] + Kinv[i * 3 + 2] * M[6 + j];
  const double p4[3] = {p[3], p[7], p[11]};
  const auto mc = mat3_vec(Minv, p4);
  out.centre = {-mc[0], -mc[1], -mc[2]};
  out.forward = {R[6], R[7], R[8]};
  out.fx = ka / kf;
  out.skew = kb / kf;
  out.cx = kc / kf;
  out.fy = kd / kf;
  out.cy = ke / kf;
  if (std::fabs(out.skew) > options.max_skew * out.fx || std::fabs(out.fx / out.fy - 1.0) > options.max_aspect_error)
    throw CameraRecoveryError("the recovered camera has skew " + num("%.3g", out.skew / out.fx) + " and pixel aspect " +
                              num("%.4g", out.fx / out.fy) + " (limits " + num("%g", options.max_skew) + ", 1 ± " +
                              num("%g", options.max_aspect_error) +
                              "): non-square pixels? In Blender, Output → Format → Aspect X and Y must be equal");

  // ---- the protocol's matrices ----
  // view = diag(1, -1, -1, 1) [R | -R C]: the fit's camera axes are x right, y down, z forward; OpenGL's y up, z back.
  const double t[3] = {-(R[0] * out.centre[0] + R[1] * out.centre[1] + R[2] * out.centre[2]),
                       -(R[3] * out.centre[0] + R[4] * out.centre[1] + R[5] * out.centre[2]),
                       -(R[6] * out.centre[0] + R[7] * out.centre[1] + R[8] * out.centre[2])};
  const double flip[3] = {1, -1, -1};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.view[size_t(c * 4 + r)] = float(flip[r] * R[r * 3 + c]);
    out.view[size_t(12 + r)] = float(flip[r] * t[r]);
  }
  out.view[15] = 1.0f;
  out.near_plane = 0.5 * dmin;
  out.far_plane = 2.0 * dmax;
  const double n = out.near_plane, f = out.far_plane, W = width, H = height;
  // Rows of the projection (derivation in docs/client.md): x_clip = 2fx/W x - 2s/W y + (1 - 2cx/W) z,
  // y_clip = 2fy/H y + (2cy/H - 1) z, z_clip = -(f+n)/(f-n) z - 2fn/(f-n), w_clip = -z.
  const double rows[4][4] = {{2 * out.fx / W, -2 * out.skew / W, 1 - 2 * out.cx / W, 0},
                             {0, 2 * out.fy / H, 2 * out.cy / H - 1, 0},
                             {0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)},
                             {0, 0, -1, 0}};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.projection[size_t(c * 4 + r)] = float(rows[r][c]);
  return out;
}

const char* to_string(FrameCameras::Source s) {
  switch (s) {
    case FrameCameras::Source::File: return "camera file";
    case FrameCameras::Source::Header: return "EXR header";
    case FrameCameras::Source::Recovered: return "Position pass";
    case FrameCameras::Source::Identity: return "identity";
  }
  return "?";
}

CameraRecoveryError::CameraRecoveryError(const std::string& reason)
    : std::runtime_error(reason + "; " + kCliChannelSyntax.camera_hint()), reason_(reason) {}

struct FrameCameras::Impl {
  ChannelSyntax syntax;
  std::string file_path;
  std::map<long long, FileCamera> file;
  mutable std::mutex mutex;
  std::map<long long, Record> records;
};

FrameCameras::FrameCameras(const std::string& camera_file, const Preset& preset,
                           const std::vector<std::string>& exr_channels, bool needs_camera,
                           const ChannelSyntax& syntax)
    : impl_(std::make_shared<Impl>()), needs_camera_(needs_camera) {
  impl_->syntax = syntax;
  if (!camera_file.empty()) {
    impl_->file_path = camera_file;
    impl_->file = read_camera_file(camera_file);
    return;
  }
  if (!needs_camera) return;  // nothing uses it: no recovery
  for (const ChannelSpec& spec : preset.channels) {
    if (spec.id == protocol::ChannelId::Position) position_ = resolve(spec, exr_channels, preset.layer_prefix);
    if (spec.id == protocol::ChannelId::Depth) depth_ = resolve(spec, exr_channels, preset.layer_prefix);
  }
}

FrameCameras::Source FrameCameras::apply(const dn::image::ExrReader& exr, long long number,
                                         dn::image::ExrCamera& camera) {
  Record rec;
  const std::string frame = "frame " + std::to_string(number) + ": ";
  if (!impl_->file_path.empty()) {
    auto it = impl_->file.find(number);
    if (it == impl_->file.end())
      throw std::runtime_error(frame + "camera file " + impl_->file_path + " has no line 'frame " +
                               std::to_string(number) + " ...'");
    camera.view = it->second.view;
    camera.projection = it->second.projection;
    camera.jitter = it->second.jitter;
    // The header's previous camera (if any) belongs to the header's camera; the client fills it from the last frame.
    camera.prev_view.reset();
    camera.prev_projection.reset();
    camera.prev_jitter.reset();
    rec.source = Source::File;
  } else if (camera.view && camera.projection) {
    rec.source = Source::Header;
  } else {
    auto has_all = [&](const std::optional<ResolvedChannel>& ch) {
      if (!ch) return false;
      for (const auto& term : ch->terms)
        for (const auto& name : term)
          if (!exr.has_channel(name)) return false;
      return true;
    };
    if (has_all(position_)) {
      std::vector<ResolvedChannel> plan{*position_};
      const bool with_depth = has_all(depth_);
      if (with_depth) plan.push_back(*depth_);
      const LoadedFrame f = load_frame(exr, plan, number);
      try {
        const RecoveredCamera c = recover_camera(f.planes[0].data, f.width, f.height,
                                                 with_depth ? std::span<const float>(f.planes[1].data)
                                                            : std::span<const float>());
        camera.view = c.view;
        camera.projection = c.projection;
        rec = {Source::Recovered, c.rms_px, c.max_px, c.points};
      } catch (const CameraRecoveryError& e) {
        throw std::runtime_error(frame + exr.path() + ": no camera in the header, and none from the Position pass: " +
                                 e.reason() + "; " + impl_->syntax.camera_hint());
      }
    } else if (needs_camera_) {
      throw std::runtime_error(
          frame + exr.path() +
          " has no camera: no dn.view / dn.projection header attributes and no Position pass to recover it from, "
          "but the pipeline, or a channel made for it, uses the camera; enable the Position pass "
          "(Blender: View Layer → Passes → Data → Position) or " + impl_->syntax.camera_hint());
    }
  }
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->records[number] = rec;
  return rec.source;
}

std::optional<FrameCameras::Record> FrameCameras::record(long long number) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  auto it = impl_->records.find(number);
  if (it == impl_->records.end()) return std::nullopt;
  return it->second;
}

std::string FrameCameras::summary() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  std::map<Source, size_t> counts;
  double worst = -1;
  long long worst_frame = 0;
  for (const auto& [n, r] : impl_->records) {
    counts[r.source]++;
    if (r.source == Source::Recovered && r.rms_px > worst) {
      worst = r.rms_px;
      worst_frame = n;
    }
  }
  std::string s = "camera:";
  bool first = true;
  for (const auto& [src, n] : counts) {
    s += std::string(first ? " " : ", ") + to_string(src) + " for " + std::to_string(n) + " frame" + (n == 1 ? "" : "s");
    first = false;
  }
  if (worst >= 0)
    s += "; recovered camera's RMS reprojection residual at most " + num("%.3f", worst) + " px (frame " +
         std::to_string(worst_frame) + ")";
  return s;
}

}  // namespace dn::cli
