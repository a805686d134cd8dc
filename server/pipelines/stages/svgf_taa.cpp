#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

void add_taa(GraphSpec& g, const TaaStage& stage) {
  PassSpec& taa = g.add_pass("svgf_taa", "svgf_taa");
  taa.bind("current", stage.buffers.current)
      .bind("previous", stage.buffers.previous)
      .bind("history", stage.buffers.history)
      .bind("depth", stage.depth);
  bind_target(taa, stage.target);
  if (stage.display_lag) taa.set("DISPLAY_LAG", 1u);
}

}  // namespace dn::pipelines::svgf
