// "A camera without headers": recovers a frame's pinhole camera from its
// world-space Position pass, for renderers (Blender Cycles) whose EXRs carry
// no camera matrices. docs/client.md, "Cameras without headers".
//
// Method: a stratified subsample (at most `max_samples` pixels) of the
// foreground pixels gives 3D-2D pairs world position -> pixel centre
// (x + 0.5, y + 0.5), y down. The 3x4 projection P is fitted by the
// normalised DLT (Hartley: points centred and scaled to mean distance
// sqrt(3) / sqrt(2)), refined by Levenberg-Marquardt on the reprojection error,
// with outliers (silhouette pixels whose filtered position mixes two surfaces)
// dropped in a few rounds. P = K [R | -R C] is then decomposed (K upper
// triangular from M M^T, the camera centre C = -M^-1 p4) into the protocol's
// OpenGL-convention view and unjittered projection (docs/protocol.md §5.6.1).
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "presets.hpp"

namespace dn::cli {

// The Position pass does not describe a usable pinhole camera. reason() says
// why; what() adds the CLI's suggestion (--camera FILE).
class CameraRecoveryError : public std::runtime_error {
 public:
  explicit CameraRecoveryError(const std::string& reason);
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

struct CameraRecoveryOptions {
  size_t max_samples = 4096;      // stratified pixel grid, at most this many pixels
  size_t min_points = 12;         // fewer usable pixels: refused
  double max_rms_px = 1.5;        // RMS reprojection residual above this: not a pinhole camera
  double max_outlier_fraction = 0.25;  // more pixels than this rejected as outliers: not a pinhole camera
  double max_skew = 0.02;         // |skew| / f
  double max_aspect_error = 0.02;  // |fx / fy - 1|
  double planarity = 1e-3;        // thinnest / widest extent of the points below this: coplanar, refused
};

struct RecoveredCamera {
  std::array<float, 16> view{};        // world -> view, column-major, OpenGL convention
  std::array<float, 16> projection{};  // view -> clip, unjittered
  std::array<double, 12> pixel_projection{};  // P, row-major 3x4: world -> pixel (y down), scaled so |M row 3| = 1
  std::array<double, 3> centre{};      // camera position, world
  std::array<double, 3> forward{};     // unit viewing direction, world
  double fx = 0, fy = 0, skew = 0, cx = 0, cy = 0;  // intrinsics, pixels (y down)
  double near_plane = 0, far_plane = 0;  // chosen: 0.5 x nearest, 2 x farthest inlier depth
  double rms_px = 0, max_px = 0;       // reprojection residual of the inliers
  size_t points = 0;                   // inliers used in the final fit
  size_t rejected = 0;                 // outliers dropped
};

// positions: width*height*3 floats (xyz per pixel, rows top-first). A pixel is
// background (not used) when a component is non-finite, when all three are
// exactly 0 (Cycles writes 0 for background), or, with `depth` (width*height
// floats), when its depth is not finite and > 0 (the protocol's background
// marker; dnrender puts background "positions" 10^4 m along the ray, which a
// fit does not need). Throws CameraRecoveryError.
RecoveredCamera recover_camera(std::span<const float> positions, int width, int height,
                               std::span<const float> depth = {}, const CameraRecoveryOptions& options = {});

// dn denoise's camera choice per frame: --camera FILE > the EXR header's dn.*
// attributes > recovered from the Position pass > identity. `needs_camera`
// (plan_needs_camera): without it nothing is recovered (identity unless a file
// or header gives one); with it a frame without a camera is an error.
class FrameCameras {
 public:
  enum class Source { File, Header, Recovered, Identity };
  // `camera_file`: path of a --camera file (camera_file.hpp) or empty.
  // `syntax`: how the caller names a camera file, for its errors.
  FrameCameras(const std::string& camera_file, const Preset& preset, const std::vector<std::string>& exr_channels,
               bool needs_camera, const ChannelSyntax& syntax = kCliChannelSyntax);

  // Sets camera.view / camera.projection (and jitter from a file) for frame
  // `number` of `exr`, unless the header already has them. Thread-safe; call
  // from the loader. Throws std::runtime_error naming the frame.
  Source apply(const dn::image::ExrReader& exr, long long number, dn::image::ExrCamera& camera);

  // What was used for frame `number` and, when recovered, its residual.
  struct Record {
    Source source = Source::Identity;
    double rms_px = 0, max_px = 0;
    size_t points = 0;
  };
  std::optional<Record> record(long long number) const;
  // One line for the run's summary: "camera: recovered from ... for 8 frames, residual RMS max 0.21 px (frame 3)".
  std::string summary() const;
  bool recovers() const { return position_.has_value(); }

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
  std::optional<ResolvedChannel> position_, depth_;
  bool needs_camera_ = false;
};

const char* to_string(FrameCameras::Source s);

}  // namespace dn::cli
