#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

void bind_validity_mask(PassSpec& pass, const std::string& mask) {
  pass.bind("sample_count", mask).set("MASKED", 1u);
}

void bind_second_geometry(PassSpec& pass, const SignalChain& first, const SignalChain& second) {
  pass.bind("temporal2", second.temporal);
  if (second.guide != first.guide) pass.bind("guide2", second.guide).set("SECOND_GUIDE", 1u);
}

void bind_target(PassSpec& pass, const FrameTarget& target) {
  if (target.display) pass.bind("display", target.buffer).set("TO_DISPLAY", 1u);
  else pass.bind("result", target.buffer);
}

}  // namespace dn::pipelines::svgf
