#include "pipelines/stages/fb_factor.hpp"

#include "pipelines/stages/fb_lut.hpp"

namespace dn::pipelines {

using protocol::ChannelId;

const SharedResourceDecl kFbLutResource{"fb_lut", fb_lut_buffer};

void add_fb_factor(GraphSpec& g, const SessionConfig& config, const std::string& factor) {
  g.add_input(config, ChannelId::SpecularF0, "specular_f0");
  g.add_shared(kFbLutResource.name, kFbLutResource.resource);
  g.add_scratch(factor);
  g.add_pass("svgf_fb_factor", "svgf_fb_factor")
      .bind("specular_f0", "specular_f0")
      .bind("roughness", "roughness")
      .bind("normal", "normal")
      .bind("depth", "depth")
      .bind("fb_lut", kFbLutResource.name)
      .bind("factor", factor)
      .pixels_per_invocation = 1;
}

}  // namespace dn::pipelines
