// The parameter table (server/pipelines/<folder>/parameters.def) without slot numbers:
// groups, the constants block's parameter struct, and the checks on groups.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string_view>

#include "pipelines/definitions.hpp"
#include "pipelines/frame_constants.hpp"
#include "pipelines/parameters.hpp"

namespace dn {
namespace {

using pipelines::ParameterGroups;

TEST(ParameterTable, EveryRowIsOneFloatOfTheUniformBlockInRowOrder) {
  const pipelines::Parameters p;
  const auto& table = pipelines::parameter_table();
  ASSERT_FALSE(table.empty());
  for (size_t i = 0; i < table.size(); ++i) {
    const auto offset = reinterpret_cast<const char*>(&(p.*table[i].member)) - reinterpret_cast<const char*>(&p);
    EXPECT_EQ(offset, static_cast<std::ptrdiff_t>(i * sizeof(float))) << table[i].info.name;
  }
  EXPECT_EQ(sizeof(pipelines::Parameters), (table.size() * sizeof(float) + 15) / 16 * 16);
  EXPECT_EQ(offsetof(pipelines::FrameConstants, params) % 16, 0u);
}

TEST(ParameterTable, GroupsAreDeclaredPerPipeline) {
  for (const auto& def : pipelines::definitions()) {
    SCOPED_TRACE(def.description.name);
    EXPECT_EQ(pipelines::parameters_of(def.parameter_groups, def.parameter_defaults).size(),
              def.description.parameters.size());
  }
  const std::string_view fb[] = {"svgf"};
  const auto block = pipelines::parameter_block(fb, {{"phi_colour", 4}});
  EXPECT_EQ(block.svgf_phi_colour, 4.0f);
  EXPECT_EQ(block.svgf_atrous_iterations, 4.0f);  // default
  EXPECT_EQ(block.accumulate_max_history, 0.0f);  // not a group svgf-fb takes
}

// A pipeline's own defaults (e.g. for the rows of a group it shares) replace the
// row's default for that pipeline only; a client's value still wins.
TEST(ParameterTable, PipelineDefaultsReplaceTheRowsDefaults) {
  const std::string_view svgf[] = {"svgf"};
  const pipelines::ParameterDefaults own = {{"atrous_iterations", 5}, {"alpha_colour", 0.1}};
  const auto block = pipelines::parameter_block(svgf, {{"alpha_colour", 0.3}}, own);
  EXPECT_EQ(block.svgf_atrous_iterations, 5.0f);
  EXPECT_EQ(block.svgf_alpha_colour, 0.3f);
  EXPECT_EQ(block.svgf_phi_normal, 128.0f);  // no own default: the row's
  const auto infos = pipelines::parameters_of(svgf, own);
  for (const auto& info : infos)
    if (info.name == "atrous_iterations") EXPECT_EQ(info.default_value, 5.0);
  EXPECT_EQ(pipelines::parameter_block(svgf, {}).svgf_atrous_iterations, 4.0f);
  EXPECT_EQ(pipelines::resolve_parameters("svgf", {})[3], 4.0f);  // atrous_iterations, the fourth row of svgf's group
  // A default must name a row of the groups and be a value validate() accepts.
  EXPECT_THROW(pipelines::parameters_of(svgf, {{"radius", 6}}), std::logic_error);
  EXPECT_THROW(pipelines::parameters_of(svgf, {{"alpha_colour", 2}}), std::logic_error);
  EXPECT_THROW(pipelines::parameters_of(svgf, {{"atrous_iterations", 4.5}}), std::logic_error);
}

TEST(ParameterTable, UnknownGroupsAndClashingNamesAreRejected) {
  const std::string_view unknown[] = {"svgf", "svgf-fb"};  // groups are identifiers, pipelines are not
  EXPECT_THROW(pipelines::parameters_of(unknown), std::logic_error);
  const std::string_view clash[] = {"accumulate", "svgf"};  // both have max_history
  EXPECT_THROW(pipelines::parameters_of(clash), std::logic_error);
}

}  // namespace
}  // namespace dn
