// Frame sequences on disk: path patterns ("frame_%04d.exr", "frame_####.exr")
// and loading one EXR frame into protocol planes through a channel plan.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "presets.hpp"

namespace dn::cli {

// True when the pattern has a frame-number placeholder: printf-style %d /
// %0Nd, or a run of '#' (Blender style, zero-padded to the run length).
bool has_frame_placeholder(const std::string& pattern);
// Substitutes the frame number; "%%" is a literal '%'. Throws UsageError for
// other '%' conversions or more than one placeholder.
std::string format_frame_path(const std::string& pattern, long long frame);
// A pattern split at its placeholder, as file names show it ("%%" made '%'):
// frame n's path is prefix + format_frame_number(width, n) + suffix.
struct FramePattern {
  std::string prefix, suffix;
  int width = 0;  // zero-padded to this many digits (0: no padding)
};
std::optional<FramePattern> split_frame_pattern(const std::string& pattern);  // nullopt: no placeholder
std::string format_frame_number(int width, long long frame);

struct LoadedPlane {
  protocol::ChannelId id;
  std::vector<float> data;  // interleaved components, rows top-first
};

struct LoadedFrame {
  long long number = 0;
  std::string path;
  int width = 0, height = 0;
  std::vector<LoadedPlane> planes;
  dn::image::ExrCamera camera;
  // With a RoughGuidePlan: its channels (then its key), read in the same
  // pass over the file, for apply_rough_guides.
  std::vector<LoadedPlane> primary_guides;
};

// Reads the plan's channels (and `guides`' into primary_guides) from an
// open EXR, sums terms and applies the conversions. Throws ChannelMapError
// naming the channel when a mapped EXR channel is missing in this frame.
LoadedFrame load_frame(const dn::image::ExrReader& exr, const std::vector<ResolvedChannel>& plan, long long number,
                       const RoughGuidePlan* guides = nullptr);

// The conversion that needs the frame's camera (camera.projection, set by
// FrameCameras::apply): Cycles' Denoising Depth (path length from the near
// plane) to depth along the view axis, with the clip start measured against
// `exr`'s Depth pass. Throws std::runtime_error naming the frame when the plan
// has such a plane and the frame has no camera.
void apply_camera_conversions(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan,
                              const dn::image::ExrReader& exr, const ChannelSyntax& syntax = kCliChannelSyntax);

// Per-pixel guides, after apply_camera_conversions: where a pixel is not a
// mirror by guides' rule — its key (roughness) at or above guides.from or not
// finite; without a key, its depth in `frame` (the Denoising Depth's) within
// kPastPrimaryDepth of the primary depth — `frame`'s guide planes take the
// values of frame.primary_guides (loaded with `guides` by load_frame).
void apply_rough_guides(LoadedFrame& frame, const RoughGuidePlan& guides);

}  // namespace dn::cli
