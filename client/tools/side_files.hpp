// dn denoise's side files: --albedo and --normal images beside the colour
// input (EXR, PFM or PNG by extension; one file for every frame or a frame
// pattern), sent as the session's albedo and normal channels. With an EXR
// input they replace what its channel layout would give for those channels.
#pragma once

#include <string>
#include <vector>

#include "args.hpp"
#include "dn/protocol/messages.hpp"
#include "frame_source.hpp"
#include "output_image.hpp"

namespace dn::cli {

struct SideFile {
  protocol::ChannelId id = protocol::ChannelId::Albedo;
  std::string option;   // "--albedo", for messages
  std::string pattern;  // one file for every frame, or a frame pattern
  ImageFormat format = ImageFormat::Exr;
};

// The side files of the command line (options "albedo" and "normal"), in
// channel order. UsageError for an extension other than .exr, .png, .pfm, and
// for a frame pattern when the input is a single file.
std::vector<SideFile> side_files_from(const Args& args, bool input_is_sequence);

// True when a side file gives channel `id`.
bool is_side_channel(const std::vector<SideFile>& sides, protocol::ChannelId id);

// UsageError when the pipeline takes a side file's channel neither as
// required nor as optional (a null pipeline, from a server that lists none,
// is not checked).
void check_side_channels(const protocol::PipelineInfo* pipeline, const std::vector<SideFile>& sides,
                         const std::string& pipeline_name);

// `pipeline` without the side files' channels: what the input itself has to give.
protocol::PipelineInfo without_side_channels(protocol::PipelineInfo pipeline, const std::vector<SideFile>& sides);

// Reads frame.number's side files into frame.planes, each replacing a plane of
// its channel. Throws std::runtime_error naming both files and both sizes when
// a side file's size is not the frame's, image::ImageError for an unreadable one.
void add_side_planes(LoadedFrame& frame, const std::vector<SideFile>& sides);

}  // namespace dn::cli
