// dn denoise's PFM and PNG inputs: colour only, sent as the radiance channel,
// with --albedo / --normal (side_files.hpp) for the other channels a pipeline
// needs. EXR inputs go through the channel layouts of presets.hpp instead.
#pragma once

#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "frame_source.hpp"
#include "output_image.hpp"
#include "side_files.hpp"

namespace dn::cli {

// Frame `number` of a PFM or PNG colour input (pattern or single file): its
// radiance plane (a PNG made linear with the sRGB EOTF). Throws
// image::ImageError naming the file.
LoadedFrame load_colour_frame(const std::string& pattern, ImageFormat format, long long number);

// The channels such an input sends: radiance, then the side files'. Throws
// ChannelMapError naming the first channel the pipeline requires that
// neither gives (a null pipeline, from a server that lists none, is not checked).
std::vector<protocol::ChannelId> plan_colour_channels(const protocol::PipelineInfo* pipeline,
                                                      const std::string& pipeline_name,
                                                      const std::vector<SideFile>& sides,
                                                      const std::string& first_path);

}  // namespace dn::cli
