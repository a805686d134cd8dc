// Frame sequences on disk: path patterns ("frame_%04d.exr", "frame_####.exr")
// and loading one EXR frame into protocol planes through a channel plan.
#pragma once

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
};

// Reads the plan's channels from an open EXR, sums terms and applies the
// conversions. Throws ChannelMapError naming the channel when a mapped EXR
// channel is missing in this frame.
LoadedFrame load_frame(const dn::image::ExrReader& exr, const std::vector<ResolvedChannel>& plan, long long number);

// Turns the planes the plan marks as camera-space normals (Cycles' Denoising
// Normal: x right, y up, z forward) into world space with the frame's view
// (camera.view, set by FrameCameras::apply). Throws std::runtime_error naming
// the frame when such a plane exists and the frame has no camera.
void camera_normals_to_world(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan);

}  // namespace dn::cli
