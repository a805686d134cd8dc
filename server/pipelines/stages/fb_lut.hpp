// The F_beta table: BRDF pre-integration of isotropic GGX with
// height-correlated Smith masking-shadowing and Schlick Fresnel (paper 000,
// Eq. 7/8; docs/pipelines.md, "F_β LUT"), computed on the device by
// server/pipelines/stages/fb_lut.comp and looked up by shaders/include/fb_lut.glsl.
//
//   F_beta(w_o) = ∫ f_r(w_o, w_i) cos θ_i dw_i = F0 · A + B
//
// Texel (i, j): cos θ_o = (i + 0.5) / kFbLutSize, GGX α = (j + 0.5) / kFbLutSize
// (α, not perceptual roughness), stored as vec2 (A, B) fp32 at j · kFbLutSize + i.
#pragma once

#include <cstdint>
#include <vector>

#include "gpu/buffer.hpp"
#include "gpu/context.hpp"

namespace dn::pipelines {

// Texels per axis. GLSL has DN_FB_LUT_SIZE in fb_lut.glsl; a test checks they agree.
inline constexpr uint32_t kFbLutSize = 256;
// Importance samples per texel (Hammersley points, GGX half-vector sampling);
// reaches the shader as its specialization constant 1.
inline constexpr uint32_t kFbLutSamples = 1024;

class FbLut {
 public:
  // Computes the table on the device and waits. Throws gpu::Error/VulkanError.
  explicit FbLut(gpu::Context& ctx);
  FbLut(const FbLut&) = delete;
  FbLut& operator=(const FbLut&) = delete;

  // Device buffer (BufferKind::Storage): kFbLutSize² vec2 (A, B), fp32, index
  // alpha_row · kFbLutSize + cos_column. Read-only after construction.
  const gpu::Buffer& buffer() const { return table_; }
  // Wall-clock milliseconds of the computation: record, submit, wait (the
  // kernel compile before it is not counted).
  double compute_ms() const { return compute_ms_; }
  // The table copied back through a download buffer: 2 · kFbLutSize² floats,
  // A and B interleaved, in buffer order. For tests and tools.
  std::vector<float> read() const;

 private:
  gpu::Context& ctx_;
  gpu::Buffer table_;
  double compute_ms_ = 0;
};

// The context's table, computed once on first use (thread-safe: concurrent
// first callers wait for the one computation) and shared read-only by every
// session of that context. Lives until the context is destroyed.
const FbLut& fb_lut(gpu::Context& ctx);
// Its buffer: the shared resource (graph.hpp SharedResource) svgf-fb binds.
const gpu::Buffer& fb_lut_buffer(gpu::Context& ctx);

}  // namespace dn::pipelines
